#include "noctua/place/vocabulary.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <random>
#include <set>
#include <sstream>

#include "noctua/util/error.h"
#include "noctua/util/install_dirs.h"

namespace noctua::place {
namespace {

constexpr char kMagic[8] = {'N', 'O', 'C', 'T', 'V', 'O', 'C', '\0'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr char kDefaultFileName[] = "default.vocab";
constexpr int kDescriptorBits = 8 * kDescriptorBytes;

void CheckDescriptors(const cv::Mat& descriptors, const std::string& what) {
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != kDescriptorBytes) {
    throw Error(what + ": descriptors must be rows of 32 bytes (CV_8U), got " +
                std::to_string(descriptors.cols) + " columns of type " +
                std::to_string(descriptors.type()));
  }
}

Descriptor RowOf(const cv::Mat& descriptors, int row) {
  Descriptor d;
  std::memcpy(d.data(), descriptors.ptr<std::uint8_t>(row), kDescriptorBytes);
  return d;
}

// A uniform double in [0, 1) from a 64-bit generator, the same on every standard library
// (std::uniform_real_distribution is not specified bit for bit).
double Uniform(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

// The bitwise majority of `members`: a bit is set where more than half of them have it set.
Descriptor Majority(const std::vector<Descriptor>& descriptors, const std::vector<int>& members) {
  std::array<int, kDescriptorBits> counts{};
  for (int m : members) {
    const Descriptor& d = descriptors[static_cast<std::size_t>(m)];
    for (int bit = 0; bit < kDescriptorBits; ++bit) {
      counts[static_cast<std::size_t>(bit)] +=
          (d[static_cast<std::size_t>(bit / 8)] >> (bit % 8)) & 1;
    }
  }
  Descriptor centre{};
  const int half = static_cast<int>(members.size());
  for (int bit = 0; bit < kDescriptorBits; ++bit) {
    if (2 * counts[static_cast<std::size_t>(bit)] > half) {
      centre[static_cast<std::size_t>(bit / 8)] |= static_cast<std::uint8_t>(1u << (bit % 8));
    }
  }
  return centre;
}

// Greedy k-means++ seeding with Hamming distance: the first centre uniformly; for each next one,
// a few candidates drawn with probability proportional to the squared distance to the closest
// centre so far, keeping the one that leaves the least total squared distance (plain k-means++
// puts two seeds in one cluster too often for clusters of equal size, and Lloyd's iterations
// cannot undo that). Fewer than k centres when the members hold fewer distinct descriptors.
std::vector<Descriptor> SeedCentres(const std::vector<Descriptor>& descriptors,
                                    const std::vector<int>& members, int k, std::mt19937_64& rng) {
  const std::size_t n = members.size();
  const auto at = [&](std::size_t i) -> const Descriptor& {
    return descriptors[static_cast<std::size_t>(members[i])];
  };
  const auto squared = [](int d) { return static_cast<double>(d) * d; };
  std::vector<Descriptor> centres = {at(rng() % n)};
  std::vector<double> nearest(n);
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    nearest[i] = squared(HammingDistance(at(i).data(), centres[0].data()));
    total += nearest[i];
  }
  const int trials = 2 + static_cast<int>(std::log(static_cast<double>(k)));
  std::vector<double> trial_nearest(n), best_nearest(n);
  while (static_cast<int>(centres.size()) < k && total > 0.0) {
    double best_total = -1.0;
    std::size_t best = 0;
    for (int t = 0; t < trials; ++t) {
      const double target = Uniform(rng) * total;
      double cumulative = 0.0;
      std::size_t chosen = n;
      for (std::size_t i = 0; i < n && chosen == n; ++i) {
        cumulative += nearest[i];
        if (cumulative > target && nearest[i] > 0.0) chosen = i;
      }
      if (chosen == n) continue;  // rounding at the very end: draw again
      double trial_total = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        trial_nearest[i] =
            std::min(nearest[i], squared(HammingDistance(at(i).data(), at(chosen).data())));
        trial_total += trial_nearest[i];
      }
      if (best_total < 0.0 || trial_total < best_total) {
        best_total = trial_total;
        best = chosen;
        best_nearest.swap(trial_nearest);
      }
    }
    if (best_total < 0.0) break;
    centres.push_back(at(best));
    nearest.swap(best_nearest);
    total = best_total;
  }
  return centres;
}

int Nearest(const std::vector<Descriptor>& centres, const std::uint8_t* descriptor) {
  int best = 0;
  int best_distance = kDescriptorBits + 1;
  for (std::size_t c = 0; c < centres.size(); ++c) {
    const int d = HammingDistance(centres[c].data(), descriptor);
    if (d < best_distance) {
      best_distance = d;
      best = static_cast<int>(c);
    }
  }
  return best;
}

// k-majority (k-means with Hamming distance and the bitwise majority as centre) of `members`:
// the non-empty clusters, each with its centre and members.
std::vector<std::pair<Descriptor, std::vector<int>>> KMajority(
    const std::vector<Descriptor>& descriptors, const std::vector<int>& members, int k,
    int max_iterations, std::mt19937_64& rng) {
  std::vector<Descriptor> centres = SeedCentres(descriptors, members, k, rng);
  std::vector<int> assignment(members.size(), -1);
  std::vector<std::vector<int>> clusters;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    bool changed = false;
    clusters.assign(centres.size(), {});
    for (std::size_t i = 0; i < members.size(); ++i) {
      const int c = Nearest(centres, descriptors[static_cast<std::size_t>(members[i])].data());
      changed = changed || c != assignment[i];
      assignment[i] = c;
      clusters[static_cast<std::size_t>(c)].push_back(members[i]);
    }
    if (!changed) break;
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (!clusters[c].empty()) centres[c] = Majority(descriptors, clusters[c]);
    }
  }
  std::vector<std::pair<Descriptor, std::vector<int>>> result;
  for (std::size_t c = 0; c < centres.size(); ++c) {
    if (!clusters[c].empty()) result.emplace_back(centres[c], std::move(clusters[c]));
  }
  return result;
}

std::uint64_t Fnv1a(std::string_view bytes) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    hash ^= static_cast<std::uint8_t>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

void PutU32(std::string& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}
void PutU64(std::string& out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

// Little-endian reading that refuses to run past the end.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}
  std::uint32_t U32() { return static_cast<std::uint32_t>(Unsigned(4)); }
  std::uint64_t U64() { return Unsigned(8); }
  void Bytes(std::uint8_t* out, std::size_t count) {
    Need(count);
    std::memcpy(out, bytes_.data() + position_, count);
    position_ += count;
  }
  std::size_t position() const { return position_; }
  [[noreturn]] void Fail(const std::string& problem) const {
    ThrowFileError(name_, "not a usable noctua vocabulary: " + problem);
  }

 private:
  std::uint64_t Unsigned(int count) {
    Need(static_cast<std::size_t>(count));
    std::uint64_t value = 0;
    for (int i = 0; i < count; ++i) {
      value |= static_cast<std::uint64_t>(
                   static_cast<std::uint8_t>(bytes_[position_ + static_cast<std::size_t>(i)]))
               << (8 * i);
    }
    position_ += static_cast<std::size_t>(count);
    return value;
  }
  void Need(std::size_t count) const {
    if (bytes_.size() - position_ < count) Fail("truncated");
  }
  std::string_view bytes_;
  std::string name_;
  std::size_t position_ = 0;
};

}  // namespace

int HammingDistance(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int i = 0; i < kDescriptorBytes; i += 8) {
    std::uint64_t x = 0, y = 0;
    std::memcpy(&x, a + i, 8);
    std::memcpy(&y, b + i, 8);
    distance += std::popcount(x ^ y);
  }
  return distance;
}

double Score(const BowVector& a, const BowVector& b) {
  // For L1-normalised vectors 1 - |a - b|_1 / 2 is the sum over shared words of min(a_i, b_i).
  double score = 0.0;
  auto i = a.begin();
  auto j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      score += std::min(i->second, j->second);
      ++i;
      ++j;
    }
  }
  return score;
}

void VocabularyOptions::Check() const {
  CheckOption(branching >= 2 && branching <= 64, "vocabulary: branching (k) must be in [2, 64]");
  CheckOption(levels >= 1 && levels <= 8, "vocabulary: levels (L) must be in [1, 8]");
  CheckOption(std::pow(static_cast<double>(branching), levels) <= 1e7,
              "vocabulary: k^L must be at most 10^7 words");
  CheckOption(max_iterations >= 1, "vocabulary: max_iterations must be at least 1");
  CheckOption(direct_index_level >= 0 && direct_index_level <= levels,
              "vocabulary: direct_index_level must be in [0, levels]");
}

Vocabulary Vocabulary::Train(const std::vector<cv::Mat>& images, const VocabularyOptions& options) {
  options.Check();
  std::vector<Descriptor> descriptors;
  for (std::size_t i = 0; i < images.size(); ++i) {
    CheckDescriptors(images[i], "vocabulary: training image " + std::to_string(i));
    for (int r = 0; r < images[i].rows; ++r) descriptors.push_back(RowOf(images[i], r));
  }
  if (descriptors.empty()) throw Error("vocabulary: no training descriptors");
  Vocabulary vocabulary;
  vocabulary.branching_ = options.branching;
  vocabulary.levels_ = options.levels;
  vocabulary.direct_index_level_ = options.direct_index_level;
  vocabulary.BuildTree(descriptors, options);
  vocabulary.NumberWords();
  vocabulary.SetWeights(images);
  vocabulary.UpdateIdentity();
  return vocabulary;
}

void Vocabulary::BuildTree(const std::vector<Descriptor>& descriptors,
                           const VocabularyOptions& options) {
  std::mt19937_64 rng(options.seed);
  nodes_.assign(1, Node());
  std::vector<int> all(descriptors.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  std::deque<std::pair<int, std::vector<int>>> queue;
  queue.emplace_back(0, std::move(all));
  while (!queue.empty()) {
    auto [parent, members] = std::move(queue.front());
    queue.pop_front();
    std::vector<std::pair<Descriptor, std::vector<int>>> clusters;
    if (static_cast<int>(members.size()) <= branching_) {
      // Too few to cluster: each descriptor is a child of its own.
      for (int m : members)
        clusters.emplace_back(descriptors[static_cast<std::size_t>(m)], std::vector<int>{m});
    } else {
      clusters = KMajority(descriptors, members, branching_, options.max_iterations, rng);
    }
    const int level = nodes_[static_cast<std::size_t>(parent)].level + 1;
    for (auto& [centre, cluster] : clusters) {
      Node child;
      child.parent = parent;
      child.level = level;
      child.descriptor = centre;
      const int id = static_cast<int>(nodes_.size());
      nodes_[static_cast<std::size_t>(parent)].children.push_back(id);
      nodes_.push_back(child);
      if (level < levels_ && cluster.size() > 1) queue.emplace_back(id, std::move(cluster));
    }
  }
}

void Vocabulary::NumberWords() {
  words_.clear();
  word_direct_node_.clear();
  for (std::size_t n = 1; n < nodes_.size(); ++n) {
    if (!nodes_[n].children.empty()) continue;
    nodes_[n].word = static_cast<int>(words_.size());
    words_.push_back(static_cast<int>(n));
    int node = static_cast<int>(n);
    while (nodes_[static_cast<std::size_t>(node)].level > direct_index_level_) {
      node = nodes_[static_cast<std::size_t>(node)].parent;
    }
    word_direct_node_.push_back(node);
  }
}

void Vocabulary::set_direct_index_level(int level) {
  CheckOption(level >= 0 && level <= levels_, "vocabulary: direct_index_level must be in [0, L]");
  direct_index_level_ = level;
  NumberWords();
}

void Vocabulary::SetWeights(const std::vector<cv::Mat>& images) {
  std::vector<int> images_with_word(words_.size(), 0);
  int with_descriptors = 0;
  for (const cv::Mat& image : images) {
    if (image.rows == 0) continue;
    ++with_descriptors;
    std::set<int> seen;
    for (int r = 0; r < image.rows; ++r) seen.insert(WordOf(image.ptr<std::uint8_t>(r)));
    for (int word : seen) ++images_with_word[static_cast<std::size_t>(word)];
  }
  training_images_ = with_descriptors;
  for (std::size_t w = 0; w < words_.size(); ++w) {
    const int n = images_with_word[w];
    nodes_[static_cast<std::size_t>(words_[w])].weight =
        n > 0 ? std::log(static_cast<double>(with_descriptors) / n) : 0.0;
  }
}

int Vocabulary::WordOf(const std::uint8_t* descriptor) const {
  std::size_t node = 0;
  while (!nodes_[node].children.empty()) {
    int best = nodes_[node].children.front();
    int best_distance = kDescriptorBits + 1;
    for (int child : nodes_[node].children) {
      const int d =
          HammingDistance(nodes_[static_cast<std::size_t>(child)].descriptor.data(), descriptor);
      if (d < best_distance) {
        best_distance = d;
        best = child;
      }
    }
    node = static_cast<std::size_t>(best);
  }
  return nodes_[node].word;
}

BowVector Vocabulary::Transform(const cv::Mat& descriptors, FeatureVector* features) const {
  if (empty()) throw Error("vocabulary: Transform on an empty vocabulary");
  CheckDescriptors(descriptors, "vocabulary: Transform");
  BowVector bow;
  if (features != nullptr) features->clear();
  for (int r = 0; r < descriptors.rows; ++r) {
    const int word = WordOf(descriptors.ptr<std::uint8_t>(r));
    const double weight = word_weight(word);
    if (weight > 0.0) bow[word] += weight;
    if (features != nullptr) {
      (*features)[word_direct_node_[static_cast<std::size_t>(word)]].push_back(r);
    }
  }
  double total = 0.0;
  for (const auto& [word, value] : bow) total += value;
  if (total > 0.0) {
    for (auto& [word, value] : bow) value /= total;
  }
  return bow;
}

std::string Vocabulary::Serialize() const {
  std::string out(kMagic, sizeof(kMagic));
  PutU32(out, kFormatVersion);
  PutU32(out, static_cast<std::uint32_t>(branching_));
  PutU32(out, static_cast<std::uint32_t>(levels_));
  PutU32(out, kDescriptorBytes);
  PutU32(out, static_cast<std::uint32_t>(training_images_));
  PutU32(out, static_cast<std::uint32_t>(nodes_.size()));
  for (std::size_t n = 1; n < nodes_.size(); ++n) {
    PutU32(out, static_cast<std::uint32_t>(nodes_[n].parent));
    out.append(reinterpret_cast<const char*>(nodes_[n].descriptor.data()), kDescriptorBytes);
  }
  PutU32(out, static_cast<std::uint32_t>(words_.size()));
  for (int node : words_) {
    PutU32(out, static_cast<std::uint32_t>(node));
    PutU64(out, std::bit_cast<std::uint64_t>(nodes_[static_cast<std::size_t>(node)].weight));
  }
  PutU64(out, Fnv1a(out));
  return out;
}

Vocabulary Vocabulary::Parse(std::string_view bytes, const std::string& name) {
  Reader r(bytes, name);
  char magic[sizeof(kMagic)];
  r.Bytes(reinterpret_cast<std::uint8_t*>(magic), sizeof(magic));
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) r.Fail("wrong magic bytes");
  const std::uint32_t version = r.U32();
  if (version != kFormatVersion) {
    r.Fail("format version " + std::to_string(version) + ", this build reads version " +
           std::to_string(kFormatVersion));
  }
  if (bytes.size() < 8 + sizeof(kMagic) + 4 ||
      Fnv1a(bytes.substr(0, bytes.size() - 8)) !=
          Reader(bytes.substr(bytes.size() - 8), name).U64()) {
    r.Fail("checksum mismatch (damaged file)");
  }
  Vocabulary v;
  v.branching_ = static_cast<int>(r.U32());
  v.levels_ = static_cast<int>(r.U32());
  if (r.U32() != kDescriptorBytes) r.Fail("descriptors are not 32 bytes");
  v.training_images_ = static_cast<int>(r.U32());
  const std::uint32_t num_nodes = r.U32();
  // The direct-index level is no part of the file (it does not change the words): a loaded
  // vocabulary uses the default level, 2 (L when smaller); set_direct_index_level changes it.
  VocabularyOptions shape;
  shape.branching = v.branching_;
  shape.levels = v.levels_;
  shape.direct_index_level = std::min(2, v.levels_);
  try {
    shape.Check();
  } catch (const Error& error) {
    r.Fail(error.what());
  }
  if (num_nodes < 2 || num_nodes > bytes.size() / kDescriptorBytes) r.Fail("bad node count");
  v.direct_index_level_ = shape.direct_index_level;
  v.nodes_.assign(num_nodes, Node());
  for (std::size_t n = 1; n < num_nodes; ++n) {
    const std::uint32_t parent = r.U32();
    if (parent >= n) r.Fail("node " + std::to_string(n) + " has a bad parent");
    Node& node = v.nodes_[n];
    node.parent = static_cast<int>(parent);
    node.level = v.nodes_[parent].level + 1;
    if (node.level > v.levels_) r.Fail("node " + std::to_string(n) + " is deeper than L");
    r.Bytes(node.descriptor.data(), kDescriptorBytes);
    Node& up = v.nodes_[parent];
    up.children.push_back(static_cast<int>(n));
    if (static_cast<int>(up.children.size()) > v.branching_)
      r.Fail("a node has more than k children");
  }
  v.NumberWords();
  const std::uint32_t num_words = r.U32();
  if (num_words != v.words_.size()) r.Fail("word count does not match the tree's leaves");
  for (std::size_t w = 0; w < num_words; ++w) {
    if (r.U32() != static_cast<std::uint32_t>(v.words_[w])) r.Fail("words out of order");
    const double weight = std::bit_cast<double>(r.U64());
    if (!std::isfinite(weight) || weight < 0.0) r.Fail("bad word weight");
    v.nodes_[static_cast<std::size_t>(v.words_[w])].weight = weight;
  }
  if (r.position() + 8 != bytes.size()) r.Fail("trailing bytes");
  v.UpdateIdentity();
  return v;
}

void Vocabulary::UpdateIdentity() {
  const std::string bytes = Serialize();
  std::ostringstream out;
  out << 'k' << branching_ << 'L' << levels_ << '-' << std::hex << std::setw(16)
      << std::setfill('0') << Fnv1a(bytes);
  identity_ = out.str();
}

void Vocabulary::Save(const std::filesystem::path& path) const {
  const std::string bytes = Serialize();
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) ThrowFileError(path, "cannot write the vocabulary");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) ThrowFileError(path, "cannot write the vocabulary: " + error.message());
}

Vocabulary Vocabulary::Load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowFileError(path, "cannot read the vocabulary file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return Parse(buffer.str(), path.string());
}

std::filesystem::path FindDefaultVocabulary() {
  if (const char* env = std::getenv("NOCTUA_VOCABULARY"); env != nullptr && *env != '\0') {
    return env;
  }
  const std::vector<std::filesystem::path> candidates = {
      ExecutableDir() / ".." / "share" / "noctua" / "vocabulary" / kDefaultFileName,
      std::filesystem::path(NOCTUA_PLACE_INSTALLED_VOCABULARY_DIR) / kDefaultFileName,
      std::filesystem::path(NOCTUA_PLACE_SOURCE_VOCABULARY_DIR) / kDefaultFileName};
  for (const auto& candidate : candidates) {
    std::error_code error;
    if (std::filesystem::is_regular_file(candidate, error)) {
      return std::filesystem::weakly_canonical(candidate);
    }
  }
  return {};
}

std::shared_ptr<const Vocabulary> LoadVocabularyShared(const std::filesystem::path& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Vocabulary>> loaded;
  // Keyed by the file's contents as far as the file system tells: a file written again is read
  // again.
  std::error_code error;
  std::string key = std::filesystem::weakly_canonical(path, error).string();
  key += '|' + std::to_string(std::filesystem::file_size(path, error));
  key += '|' +
         std::to_string(std::filesystem::last_write_time(path, error).time_since_epoch().count());
  std::lock_guard lock(mutex);
  auto it = loaded.find(key);
  if (it == loaded.end()) {
    it = loaded.emplace(key, std::make_shared<const Vocabulary>(Vocabulary::Load(path))).first;
  }
  return it->second;
}

}  // namespace noctua::place
