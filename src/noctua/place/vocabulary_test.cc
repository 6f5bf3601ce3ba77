#include "noctua/place/vocabulary.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include "noctua/place/place_test_support.h"
#include "noctua/util/error.h"

namespace noctua::place {
namespace {

using ::testing::HasSubstr;

// `clusters` random centres and `per_cluster` descriptors around each (each bit of the centre
// flipped with probability `noise`), spread over `images` images in turn. Random 256-bit
// centres are ~128 bits apart; 5 % noise moves a descriptor ~13 bits from its centre.
struct Clustered {
  std::vector<cv::Mat> images;
  std::vector<int> cluster_of;  // per descriptor, in image-major order
  std::vector<cv::Mat> rows;    // each descriptor alone
};
Clustered MakeClusters(int clusters, int per_cluster, int images, double noise,
                       std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Descriptor> centres(static_cast<std::size_t>(clusters));
  for (auto& centre : centres) {
    for (auto& byte : centre) byte = static_cast<std::uint8_t>(rng() & 0xff);
  }
  Clustered out;
  out.images.assign(static_cast<std::size_t>(images), cv::Mat());
  std::vector<std::vector<int>> image_clusters(static_cast<std::size_t>(images));
  int next = 0;
  for (int c = 0; c < clusters; ++c) {
    for (int m = 0; m < per_cluster; ++m) {
      cv::Mat row(1, kDescriptorBytes, CV_8U);
      for (int b = 0; b < kDescriptorBytes; ++b) {
        std::uint8_t byte = centres[static_cast<std::size_t>(c)][static_cast<std::size_t>(b)];
        for (int bit = 0; bit < 8; ++bit) {
          if (static_cast<double>(rng() >> 11) / 9007199254740992.0 < noise) {
            byte = static_cast<std::uint8_t>(byte ^ (1u << bit));
          }
        }
        row.at<std::uint8_t>(0, b) = byte;
      }
      const auto image = static_cast<std::size_t>(next++ % images);
      out.images[image].push_back(row);
      image_clusters[image].push_back(c);
    }
  }
  for (std::size_t i = 0; i < out.images.size(); ++i) {
    for (int r = 0; r < out.images[i].rows; ++r) {
      out.rows.push_back(out.images[i].row(r));
      out.cluster_of.push_back(image_clusters[i][static_cast<std::size_t>(r)]);
    }
  }
  return out;
}

// Ten well-separated clusters and a one-level tree of k = 10: every cluster becomes exactly one
// word (all its descriptors land on it and no other cluster's do), whatever the seed.
TEST(Vocabulary, TrainingRecoversGeneratedClusters) {
  const Clustered data = MakeClusters(10, 60, 12, 0.05, 7);
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    VocabularyOptions options;
    options.branching = 10;
    options.levels = 1;
    options.direct_index_level = 1;
    options.seed = seed;
    const Vocabulary vocabulary = Vocabulary::Train(data.images, options);
    ASSERT_EQ(vocabulary.num_words(), 10);
    std::map<int, int> word_of_cluster;
    std::set<int> words;
    for (std::size_t i = 0; i < data.rows.size(); ++i) {
      const int word = vocabulary.WordOf(data.rows[i].ptr<std::uint8_t>());
      const auto [it, added] = word_of_cluster.emplace(data.cluster_of[i], word);
      EXPECT_EQ(it->second, word) << "cluster " << data.cluster_of[i] << ", seed " << seed;
      words.insert(word);
    }
    EXPECT_EQ(words.size(), 10u);
    // Each word appears in every training image: no word tells images apart, weight log(1) = 0.
    for (int w = 0; w < 10; ++w) EXPECT_DOUBLE_EQ(vocabulary.word_weight(w), 0.0);
  }
}

// Two levels over 4 x 4 clusters (4 random groups ~128 bits apart, each of 4 sub-clusters 32
// bits apart, each of 40 descriptors within a bit): the first level splits the groups, the
// second the sub-clusters, and the direct index at level 1 keeps each group's features together.
TEST(Vocabulary, TwoLevelsSplitGroupsThenSubClusters) {
  std::mt19937_64 rng(11);
  std::vector<cv::Mat> images(4);
  std::vector<std::pair<int, int>> labels;  // (group, sub) of image 0's rows
  for (int g = 0; g < 4; ++g) {
    Descriptor group{};
    for (auto& byte : group) byte = static_cast<std::uint8_t>(rng() & 0xff);
    for (int s = 0; s < 4; ++s) {
      Descriptor sub = group;
      sub[static_cast<std::size_t>(2 * s)] ^= 0xff;
      sub[static_cast<std::size_t>(2 * s + 1)] ^= 0xff;
      for (int m = 0; m < 40; ++m) {
        cv::Mat row(1, kDescriptorBytes, CV_8U, sub.data());
        row = row.clone();
        const auto bit = static_cast<int>(rng() % 512);  // half of the rows get one bit flipped
        if (bit < 256)
          row.at<std::uint8_t>(0, bit / 8) ^= static_cast<std::uint8_t>(1u << (bit % 8));
        images[static_cast<std::size_t>(m % 4)].push_back(row);
        if (m % 4 == 0) labels.emplace_back(g, s);
      }
    }
  }
  VocabularyOptions options;
  options.branching = 4;
  options.levels = 2;
  options.direct_index_level = 1;
  const Vocabulary vocabulary = Vocabulary::Train(images, options);
  EXPECT_EQ(vocabulary.num_words(), 16);
  FeatureVector direct;
  const BowVector bow = vocabulary.Transform(images[0], &direct);
  EXPECT_EQ(direct.size(), 4u);
  std::map<std::pair<int, int>, int> word_of;
  for (int r = 0; r < images[0].rows; ++r) {
    const int word = vocabulary.WordOf(images[0].ptr<std::uint8_t>(r));
    const auto [it, added] = word_of.emplace(labels[static_cast<std::size_t>(r)], word);
    EXPECT_EQ(it->second, word);
  }
  EXPECT_EQ(word_of.size(), 16u);
  for (const auto& [node, features] : direct) {
    ASSERT_EQ(features.size(), 40u);  // one group: 4 sub-clusters of 10 rows in this image
    std::set<int> groups;
    for (int f : features) groups.insert(labels[static_cast<std::size_t>(f)].first);
    EXPECT_EQ(groups.size(), 1u);
  }
}

TEST(Vocabulary, TrainingTwiceWithTheSameSeedGivesTheSameBytes) {
  const Clustered data = MakeClusters(30, 40, 10, 0.1, 3);
  VocabularyOptions options;
  options.branching = 5;
  options.levels = 3;
  const std::string first = Vocabulary::Train(data.images, options).Serialize();
  EXPECT_EQ(Vocabulary::Train(data.images, options).Serialize(), first);
  options.seed = 2;
  EXPECT_NE(Vocabulary::Train(data.images, options).Serialize(), first);
}

TEST(Vocabulary, ScoreIsOneForTheSameVectorAndZeroWithoutSharedWords) {
  const BowVector a = {{1, 0.5}, {4, 0.25}, {9, 0.25}};
  const BowVector b = {{2, 0.5}, {5, 0.5}};
  const BowVector c = {{1, 0.25}, {4, 0.25}, {7, 0.5}};
  EXPECT_DOUBLE_EQ(Score(a, a), 1.0);
  EXPECT_DOUBLE_EQ(Score(a, b), 0.0);
  // 1 - (|0.5-0.25| + 0 + 0.25 + 0.5) / 2 = 0.5
  EXPECT_DOUBLE_EQ(Score(a, c), 0.5);
  EXPECT_DOUBLE_EQ(Score(c, a), 0.5);
}

// Real frames: a frame's bag of words scores 1 against itself, less against a frame a third of
// a second later, and less still against one from the other end of the sequence.
TEST(Vocabulary, RealFrameScoresOneAgainstItselfAndLessAgainstOthers) {
  const Vocabulary& vocabulary = test::OtherSceneVocabulary();
  const auto& frames = test::Fr1Descriptors();
  FeatureVector direct;
  const BowVector first = vocabulary.Transform(frames[0], &direct);
  double total = 0.0;
  for (const auto& [word, weight] : first) total += weight;
  EXPECT_NEAR(total, 1.0, 1e-12);
  int indexed = 0;
  for (const auto& [node, features] : direct) indexed += static_cast<int>(features.size());
  EXPECT_EQ(indexed, frames[0].rows);
  EXPECT_NEAR(Score(first, vocabulary.Transform(frames[0])), 1.0, 1e-12);
  const double near = Score(first, vocabulary.Transform(frames[10]));
  const double far = Score(first, vocabulary.Transform(frames[150]));
  EXPECT_LT(near, 0.9);
  EXPECT_LT(far, near);
}

class VocabularyFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("noctua_vocabulary_test_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  static void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
  }
  std::filesystem::path dir_;
};

TEST_F(VocabularyFileTest, SaveAndLoadGiveIdenticalTransforms) {
  const Vocabulary& trained = test::OtherSceneVocabulary();
  const auto path = dir_ / "v.vocab";
  trained.Save(path);
  const Vocabulary loaded = Vocabulary::Load(path);
  EXPECT_EQ(loaded.identity(), trained.identity());
  EXPECT_EQ(loaded.Serialize(), trained.Serialize());
  EXPECT_EQ(loaded.num_words(), trained.num_words());
  EXPECT_EQ(loaded.training_images(), 30);
  for (int f : {0, 77, 199}) {
    const cv::Mat& frame = test::Fr1Descriptors()[static_cast<std::size_t>(f)];
    FeatureVector a, b;
    EXPECT_EQ(loaded.Transform(frame, &a), trained.Transform(frame, &b));
    EXPECT_EQ(a, b);
  }
  EXPECT_THAT(trained.identity(), ::testing::StartsWith("k10L3-"));
}

TEST_F(VocabularyFileTest, DamagedOrForeignFilesAreRefusedNamingTheFile) {
  const std::string bytes = test::OtherSceneVocabulary().Serialize();
  const auto refused = [&](const std::string& content, const std::string& problem) {
    const auto path = dir_ / "bad.vocab";
    WriteBytes(path, content);
    EXPECT_THAT([&] { Vocabulary::Load(path); },
                ::testing::ThrowsMessage<Error>(
                    ::testing::AllOf(HasSubstr(path.string()), HasSubstr(problem))));
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x10);
  refused(flipped, "checksum");
  refused(bytes.substr(0, bytes.size() - 100), "checksum");
  refused(bytes.substr(0, 10), "truncated");
  std::string other_version = bytes;
  other_version[8] = 2;
  refused(other_version, "format version 2");
  refused("P5\n640 480\n255\n" + std::string(64, 'x'), "magic");
  EXPECT_THAT([&] { Vocabulary::Load(dir_ / "missing.vocab"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("missing.vocab")));
}

TEST(Vocabulary, BadOptionsAndDescriptorsAreRefused) {
  VocabularyOptions options;
  options.branching = 1;
  EXPECT_THAT([&] { options.Check(); }, ::testing::ThrowsMessage<Error>(HasSubstr("branching")));
  options = VocabularyOptions();
  options.direct_index_level = 5;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<Error>(HasSubstr("direct_index_level")));
  EXPECT_THAT([&] { Vocabulary::Train({cv::Mat(3, 16, CV_8U)}, VocabularyOptions()); },
              ::testing::ThrowsMessage<Error>(HasSubstr("32 bytes")));
  EXPECT_THAT([&] { Vocabulary::Train({}, VocabularyOptions()); },
              ::testing::ThrowsMessage<Error>(HasSubstr("no training descriptors")));
}

}  // namespace
}  // namespace noctua::place
