#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace noctua::place {

// Place recognition with a bag of binary words (docs/slam.md, "Place recognition"): a
// vocabulary tree over 256-bit descriptors (rBRIEF / ORB rows of 32 bytes), trained by
// hierarchical k-majority clustering; an image becomes a weighted histogram of its words.

inline constexpr int kDescriptorBytes = 32;
using Descriptor = std::array<std::uint8_t, kDescriptorBytes>;

// Word id -> tf-idf weight, L1-normalised (sums to 1); words of weight 0 are left out.
using BowVector = std::map<int, double>;
// The direct index: node id at VocabularyOptions::direct_index_level -> indices of the features
// (descriptor rows) under that node, in increasing order. Two features can only be the same
// point when they fall under the same node, so matching compares only those.
using FeatureVector = std::map<int, std::vector<int>>;

// Similarity of two L1-normalised BowVectors: 1 - |v1 - v2|_1 / 2, in [0, 1] (1: same words
// in the same proportions, 0: no word in common).
double Score(const BowVector& a, const BowVector& b);

// Hamming distance of two 256-bit descriptors.
int HammingDistance(const std::uint8_t* a, const std::uint8_t* b);

struct VocabularyOptions {
  int branching = 10;  // k: children of each node
  int levels = 3;      // L: depth of the tree; up to k^L words
  // Lloyd iterations of k-majority at each node at most (it stops earlier once no descriptor
  // changes cluster).
  int max_iterations = 10;
  std::uint64_t seed = 1;  // of the k-means++ seeding: the same seed gives the same tree
  // Level (0 = root) whose nodes key the direct index (FeatureVector). ORB-SLAM uses 4 levels
  // above the leaves of its 6-level tree, i.e. 100 nodes for k = 10; here the same with
  // direct_index_level 2. A word shallower than this level keys the direct index itself.
  int direct_index_level = 2;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// A trained vocabulary tree. Node 0 is the root; every other node has the majority descriptor of
// the training descriptors clustered under it; the leaves are the words, each with an IDF weight
// log(N / n_i) (N training images, n_i of them containing the word).
class Vocabulary {
 public:
  Vocabulary() = default;

  // Trains on the descriptors of `images` (one CV_8U matrix of 32-byte rows per training image).
  // Deterministic: the same images and options give the same tree. Throws noctua::Error for bad
  // options, descriptors that are not 32-byte CV_8U rows, or no descriptor at all.
  static Vocabulary Train(const std::vector<cv::Mat>& images, const VocabularyOptions& options);

  bool empty() const { return words_.empty(); }
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  int num_words() const { return static_cast<int>(words_.size()); }
  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  int training_images() const { return training_images_; }
  double word_weight(int word) const { return nodes_[WordNode(word)].weight; }
  const Descriptor& word_descriptor(int word) const { return nodes_[WordNode(word)].descriptor; }
  int direct_index_level() const { return direct_index_level_; }
  void set_direct_index_level(int level);

  // The word of one descriptor: down the tree to the closest child at each level (ties: the
  // first child).
  int WordOf(const std::uint8_t* descriptor) const;

  // The bag of words of an image's descriptors (32-byte CV_8U rows) and, when `features` is
  // given, its direct index. Throws noctua::Error for descriptors of another shape.
  BowVector Transform(const cv::Mat& descriptors, FeatureVector* features = nullptr) const;

  // The versioned binary format (docs/slam.md): magic bytes, version, k, L, the nodes'
  // descriptors and the words' weights, and a 64-bit FNV-1a checksum of all that. The same
  // vocabulary gives the same bytes.
  std::string Serialize() const;
  // Throws noctua::Error naming `name` for bytes that are not a vocabulary of this version, or
  // damaged or truncated ones.
  static Vocabulary Parse(std::string_view bytes, const std::string& name);
  void Save(const std::filesystem::path& path) const;
  static Vocabulary Load(const std::filesystem::path& path);

  // Names this vocabulary in saved maps: "k<k>L<L>-<checksum of the saved bytes in hex>".
  const std::string& identity() const { return identity_; }

 private:
  struct Node {
    int parent = -1;
    int level = 0;
    int word = -1;  // word id of a leaf, -1 for an inner node
    double weight = 0.0;
    Descriptor descriptor{};
    std::vector<int> children;
  };
  std::size_t WordNode(int word) const {
    return static_cast<std::size_t>(words_[static_cast<std::size_t>(word)]);
  }
  // Clusters the training descriptors node by node, breadth first, down to `levels_`.
  void BuildTree(const std::vector<Descriptor>& descriptors, const VocabularyOptions& options);
  // Words are the leaves in node order; also derives each word's direct-index node.
  void NumberWords();
  void SetWeights(const std::vector<cv::Mat>& images);
  void UpdateIdentity();

  int branching_ = 0;
  int levels_ = 0;
  int training_images_ = 0;
  int direct_index_level_ = 2;
  std::vector<Node> nodes_;
  std::vector<int> words_;  // node of each word
  std::vector<int> word_direct_node_;
  std::string identity_;
};

// The default vocabulary's file (data/vocabulary/, installed as share/noctua/vocabulary/): the
// environment variable NOCTUA_VOCABULARY when set, else the first existing of the installed
// command's <bin>/../share/noctua/vocabulary, the install prefix's and the source tree's.
// Returns an empty path when none exists.
std::filesystem::path FindDefaultVocabulary();

// Vocabulary::Load, once per path in a process: the SLAM loads the vocabulary for every run and
// map identity, so the same file is read and checked once.
std::shared_ptr<const Vocabulary> LoadVocabularyShared(const std::filesystem::path& path);

}  // namespace noctua::place
