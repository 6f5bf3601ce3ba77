#include "noctua/io/dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path Fr1Dir() { return testing::DataDir() / "tum_fr1_rpy_200"; }

class DatasetTest : public ::testing::Test {
 protected:
  fs::path dir_ = fs::temp_directory_path() / ("noctua_dataset_test_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir_); }
  void TearDown() override { fs::remove_all(dir_); }

  void WriteText(const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  // A tiny TUM-layout sequence of `count` frames at 30 Hz, depth 1 ms after colour.
  fs::path MakeTum(const std::string& name, int count,
                   cv::Mat depth = cv::Mat(4, 6, CV_16UC1, cv::Scalar(5000))) {
    const fs::path root = dir_ / name;
    std::string rgb = "# timestamp filename\n";
    std::string depth_list;
    for (int i = 0; i < count; ++i) {
      char stamp[32];
      std::snprintf(stamp, sizeof(stamp), "%.6f", 100.0 + i / 30.0);
      char depth_stamp[32];
      std::snprintf(depth_stamp, sizeof(depth_stamp), "%.6f", 100.001 + i / 30.0);
      rgb += std::string(stamp) + " rgb/" + stamp + ".png\n";
      depth_list += std::string(depth_stamp) + " depth/" + depth_stamp + ".png\n";
      fs::create_directories(root / "rgb");
      fs::create_directories(root / "depth");
      cv::imwrite((root / "rgb" / (std::string(stamp) + ".png")).string(),
                  cv::Mat(4, 6, CV_8UC3, cv::Scalar(10, 20, 30)));
      cv::imwrite((root / "depth" / (std::string(depth_stamp) + ".png")).string(), depth);
    }
    WriteText(root / "rgb.txt", rgb);
    WriteText(root / "depth.txt", depth_list);
    return root;
  }
  static std::string ErrorOf(const std::function<void()>& fn) {
    try {
      fn();
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
};

TEST_F(DatasetTest, ReadsTheRealFr1Sequence) {
  const Sequence sequence = Sequence::Open(Fr1Dir());
  EXPECT_EQ(sequence.layout(), DatasetLayout::kTum);
  ASSERT_EQ(sequence.size(), 200u);
  EXPECT_DOUBLE_EQ(sequence.frames().front().timestamp, 1305031229.528748);
  EXPECT_DOUBLE_EQ(sequence.frames().back().timestamp, 1305031236.161670);
  EXPECT_EQ(sequence.frames().front().depth_path.filename(), "1305031229.528784.png");
  EXPECT_TRUE(sequence.has_ground_truth());
  for (const Frame& frame : sequence.frames()) {
    EXPECT_TRUE(frame.ground_truth.has_value()) << frame.index;
    EXPECT_LT(std::abs(frame.depth_timestamp - frame.timestamp), 0.02);
  }
  const FrameImages images = sequence.Load(sequence.frame(0), 5000.0);
  EXPECT_EQ(images.bgr.type(), CV_8UC3);
  ASSERT_EQ(images.depth_m.type(), CV_32FC1);
  // SOURCE.md: first depth frame 71% valid, median 1.22 m.
  std::vector<float> valid;
  for (auto it = images.depth_m.begin<float>(); it != images.depth_m.end<float>(); ++it) {
    if (*it > 0.0f) valid.push_back(*it);
  }
  EXPECT_NEAR(static_cast<double>(valid.size()) / images.depth_m.total(), 0.71, 0.01);
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  EXPECT_NEAR(valid[valid.size() / 2], 1.22, 0.01);
}

TEST_F(DatasetTest, GroundTruthIsInterpolatedAtTheFrameTime) {
  const Sequence sequence = Sequence::Open(Fr1Dir());
  const Frame& frame = sequence.frame(100);
  // The two mocap lines around the frame, read here independently of the reader.
  std::ifstream in(Fr1Dir() / "groundtruth.txt");
  std::string line;
  std::vector<std::array<double, 8>> rows;
  while (std::getline(in, line)) {
    std::array<double, 8> v{};
    if (std::sscanf(line.c_str(), "%lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3],
                    &v[4], &v[5], &v[6], &v[7]) == 8) {
      rows.push_back(v);
    }
  }
  std::size_t after = 0;
  while (rows[after][0] < frame.timestamp) ++after;
  const auto& a = rows[after - 1];
  const auto& b = rows[after];
  const double alpha = (frame.timestamp - a[0]) / (b[0] - a[0]);
  ASSERT_GT(alpha, 0.0);
  ASSERT_LT(alpha, 1.0);
  const Eigen::Vector3d expected_position =
      Eigen::Vector3d(a[1], a[2], a[3]) * (1 - alpha) + Eigen::Vector3d(b[1], b[2], b[3]) * alpha;
  const Eigen::Quaterniond qa(a[7], a[4], a[5], a[6]);
  const Eigen::Quaterniond qb(b[7], b[4], b[5], b[6]);
  const Eigen::Quaterniond expected_rotation = qa.normalized().slerp(alpha, qb.normalized());
  ASSERT_TRUE(frame.ground_truth.has_value());
  EXPECT_TRUE(frame.ground_truth->translation().isApprox(expected_position, 1e-9));
  EXPECT_TRUE(
      Eigen::Quaterniond(frame.ground_truth->rotation()).isApprox(expected_rotation, 1e-9) ||
      Eigen::Quaterniond(frame.ground_truth->rotation())
          .coeffs()
          .isApprox(-expected_rotation.coeffs(), 1e-9));
}

TEST_F(DatasetTest, AssociationByTimestampReproducesTheGivenAssociations) {
  const fs::path copy = dir_ / "fr1_lists_only";
  fs::create_directories(copy);
  fs::copy_file(Fr1Dir() / "rgb.txt", copy / "rgb.txt");
  fs::copy_file(Fr1Dir() / "depth.txt", copy / "depth.txt");
  fs::create_directory_symlink(Fr1Dir() / "rgb", copy / "rgb");
  fs::create_directory_symlink(Fr1Dir() / "depth", copy / "depth");
  const Sequence associated = Sequence::Open(copy);
  EXPECT_FALSE(associated.has_ground_truth());
  const auto given = ReadAssociationList(Fr1Dir() / "associations.txt");
  ASSERT_EQ(associated.size(), given.size());
  for (std::size_t i = 0; i < given.size(); ++i) {
    EXPECT_DOUBLE_EQ(associated.frame(i).timestamp, given[i].rgb.timestamp);
    EXPECT_DOUBLE_EQ(associated.frame(i).depth_timestamp, given[i].depth.timestamp);
  }
}

TEST_F(DatasetTest, AcceptsTheRealFr3AssociationLists) {
  const std::map<std::string, std::size_t> counts = {
      {"fr3_walking_rpy", 866},    {"fr3_walking_xyz", 827},
      {"fr3_walking_static", 717}, {"fr3_walking_halfsphere", 1021},
      {"fr3_sitting_rpy", 795},    {"fr3_sitting_xyz", 1219},
      {"fr3_sitting_static", 680}, {"fr3_sitting_halfsphere", 1074}};
  for (const auto& [name, count] : counts) {
    const auto pairs = ReadAssociationList(testing::DataDir() / "tum_fr3_meta" / (name + ".txt"));
    ASSERT_EQ(pairs.size(), count) << name;
    for (const RgbdPair& pair : pairs) {
      EXPECT_LT(std::abs(pair.rgb.timestamp - pair.depth.timestamp), 0.02) << name;
      EXPECT_EQ(pair.rgb.file.substr(0, 4), "rgb/");
    }
  }
  const auto walking_rpy =
      ReadAssociationList(testing::DataDir() / "tum_fr3_meta" / "fr3_walking_rpy.txt");
  EXPECT_DOUBLE_EQ(walking_rpy.front().rgb.timestamp, 1341846647.802247);
  EXPECT_DOUBLE_EQ(walking_rpy.back().rgb.timestamp, 1341846678.439991);
}

TEST_F(DatasetTest, AssociationPairsEachImageOnceWithinTheWindow) {
  const std::vector<TimedFile> rgb = {{1.00, "a", 1}, {1.03, "b", 2}, {1.10, "c", 3}};
  const std::vector<TimedFile> depth = {{1.015, "x", 1}, {1.02, "y", 2}, {1.5, "z", 3}};
  const auto pairs = AssociateByTimestamp(rgb, depth, 0.02);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].rgb.file + pairs[0].depth.file, "ax");  // y is taken by b (closer)
  EXPECT_EQ(pairs[1].rgb.file + pairs[1].depth.file, "by");
}

TEST_F(DatasetTest, ReadsOpenLorisLayout) {
  const fs::path root = dir_ / "loris";
  fs::create_directories(root / "color");
  fs::create_directories(root / "aligned_depth");
  for (const char* stamp : {"1560000000.000000", "1560000000.033333", "1560000000.066667"}) {
    cv::imwrite((root / "color" / (std::string(stamp) + ".png")).string(),
                cv::Mat(4, 6, CV_8UC3, cv::Scalar(1, 2, 3)));
    cv::imwrite((root / "aligned_depth" / (std::string(stamp) + ".png")).string(),
                cv::Mat(4, 6, CV_16UC1, cv::Scalar(1500)));
  }
  WriteText(root / "groundtruth.txt",
            "# timestamp tx ty tz qx qy qz qw\n1559999999.9 0 0 0 0 0 0 1\n"
            "1560000000.1 2 0 0 0 0 0 1\n");
  // The two poses are 0.2 s apart: beyond the default gap, within a wider one.
  EXPECT_FALSE(Sequence::Open(root).frame(0).ground_truth.has_value());
  const Sequence sequence = Sequence::Open(root, {.max_ground_truth_gap_s = 0.5});
  EXPECT_EQ(sequence.layout(), DatasetLayout::kOpenLoris);
  ASSERT_EQ(sequence.size(), 3u);
  ASSERT_TRUE(sequence.frame(0).ground_truth.has_value());
  EXPECT_NEAR(sequence.frame(0).ground_truth->translation().x(), 1.0, 1e-6);
  const FrameImages images = sequence.Load(sequence.frame(2), 1000.0);
  EXPECT_FLOAT_EQ(images.depth_m.at<float>(0, 0), 1.5f);
}

TEST_F(DatasetTest, BadSequencesFailNamingFileAndLine) {
  const fs::path good = MakeTum("good", 3);
  EXPECT_EQ(Sequence::Open(good).size(), 3u);

  const fs::path malformed = MakeTum("malformed", 3);
  WriteText(malformed / "rgb.txt", "# header\n100.000000 rgb/100.000000.png\n100.03 \n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(malformed); }),
              HasSubstr("rgb.txt:3: expected 'timestamp file', found 1 fields"));
  WriteText(malformed / "rgb.txt", "abc rgb/100.000000.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(malformed); }), HasSubstr("rgb.txt:1: 'abc' is not"));

  const fs::path missing = MakeTum("missing", 3);
  fs::remove(missing / "rgb" / "100.033333.png");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(missing); }),
              HasSubstr("rgb.txt:3: " + (missing / "rgb" / "100.033333.png").string() +
                        ": no such image file"));

  const fs::path empty = MakeTum("empty", 0);
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(empty); }), HasSubstr("the sequence has no frames"));

  const fs::path far = MakeTum("far", 2);
  WriteText(far / "depth.txt", "200.0 depth/100.001000.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(far); }),
              HasSubstr("rgb.txt: the sequence has no frames"));

  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_); }), HasSubstr("not a dataset folder"));
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(dir_ / "absent"); }),
              HasSubstr("no such dataset folder"));

  const fs::path eight_bit = MakeTum("eight_bit", 1, cv::Mat(4, 6, CV_8UC1, cv::Scalar(9)));
  const Sequence eight = Sequence::Open(eight_bit);
  EXPECT_THAT(ErrorOf([&] { eight.Load(eight.frame(0), 5000.0); }),
              HasSubstr("expected a 16-bit single-channel depth image"));

  const fs::path mismatch = MakeTum("mismatch", 1, cv::Mat(8, 6, CV_16UC1, cv::Scalar(9)));
  const Sequence mismatched = Sequence::Open(mismatch);
  EXPECT_THAT(ErrorOf([&] { mismatched.Load(mismatched.frame(0), 5000.0); }),
              HasSubstr("depth image is 6x8 but its colour image 100.000000.png is 6x4"));

  const fs::path bad_gt = MakeTum("bad_gt", 1);
  WriteText(bad_gt / "groundtruth.txt", "1 2 3\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(bad_gt); }),
              HasSubstr("groundtruth.txt:1: expected 8 fields"));

  WriteText(good / "associations.txt", "100.0 rgb/100.000000.png 100.001 depth/nope.png\n");
  EXPECT_THAT(ErrorOf([&] { Sequence::Open(good); }),
              HasSubstr("associations.txt:1: " + (good / "depth" / "nope.png").string()));
}

}  // namespace
}  // namespace noctua::io
