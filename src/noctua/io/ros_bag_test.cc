#include "noctua/io/ros_bag.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "noctua/io/frame_source.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr double kTumDepthFactor = 5000.0;

class RosBagTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sequence_ = new Sequence(Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200"));
  }
  static void TearDownTestSuite() {
    delete sequence_;
    sequence_ = nullptr;
  }
  void SetUp() override { fs::create_directories(dir_); }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path Write(const std::string& name, const RosBagWriteOptions& options) {
    const fs::path path = dir_ / name;
    WriteRosBag(*sequence_, kTumDepthFactor, path, options);
    return path;
  }
  // The message of Open()'s noctua::Error, or "" when it opened.
  static std::string OpenError(const fs::path& path, const RosBagOptions& options = {}) {
    try {
      RosBagSource::Open(path, options);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }

  static Sequence* sequence_;
  fs::path dir_ = fs::temp_directory_path() / ("noctua_ros_bag_test_" + std::to_string(::getpid()));
};

Sequence* RosBagTest::sequence_ = nullptr;

// Every encoding the reader accepts gives back the folder's frames: same times, same colour,
// same depth (16UC1 to the millimetre it holds).
TEST_F(RosBagTest, ReadsBackTheFramesItWroteInEveryEncoding) {
  for (const auto& [rgb, depth] : {std::pair{"rgb8", "32FC1"}, std::pair{"bgr8", "16UC1"}}) {
    SCOPED_TRACE(std::string(rgb) + " " + depth);
    RosBagWriteOptions options;
    options.rgb_encoding = rgb;
    options.depth_encoding = depth;
    options.max_frames = 8;
    const fs::path path = Write(std::string(rgb) + ".bag", options);
    const auto bag = RosBagSource::Open(path);
    ASSERT_EQ(bag->size(), 8U);
    for (int i = 0; i < 8; ++i) {
      const std::optional<SourceFrame> frame = bag->Next();
      ASSERT_TRUE(frame.has_value());
      const Frame& expected = sequence_->frame(static_cast<std::size_t>(i));
      EXPECT_EQ(frame->index, i);
      EXPECT_NEAR(frame->timestamp, expected.timestamp, 1e-6);
      EXPECT_NEAR(bag->pairs()[i].depth.timestamp, expected.depth_timestamp, 1e-6);
      const FrameImages images = sequence_->Load(expected, kTumDepthFactor);
      EXPECT_EQ(cv::norm(frame->images.bgr, images.bgr, cv::NORM_INF), 0.0);
      ASSERT_EQ(frame->images.depth_m.type(), CV_32FC1);
      const double tolerance = std::string(depth) == "16UC1" ? 0.0005 + 1e-6 : 0.0;
      EXPECT_LE(cv::norm(frame->images.depth_m, images.depth_m, cv::NORM_INF), tolerance);
      // No measurement stays no measurement (NaN in 32FC1, 0 in 16UC1).
      EXPECT_EQ(cv::countNonZero(frame->images.depth_m == 0.0F),
                cv::countNonZero(images.depth_m == 0.0F));
    }
    EXPECT_FALSE(bag->Next().has_value());
  }
}

TEST_F(RosBagTest, OpenFrameSourceReadsABagWithItsGroundTruthAndFrameLimit) {
  RosBagWriteOptions write;
  write.max_frames = 6;
  FrameSourceOptions options;
  options.bag = Write("gt.bag", write);
  options.ground_truth = testing::DataDir() / "tum_fr1_rpy_200" / "groundtruth.txt";
  options.max_frames = 4;
  const auto source = OpenFrameSource(options);
  EXPECT_EQ(source->size(), 4U);
  EXPECT_EQ(source->ground_truth().size(), sequence_->ground_truth().size());
  EXPECT_THAT(source->Describe(), HasSubstr("gt.bag"));
}

TEST_F(RosBagTest, ATopicWithoutImagesNamesTheTopicAndListsTheBagsImageTopics) {
  RosBagWriteOptions write;
  write.max_frames = 2;
  write.rgb_topic = "/cam/color";
  const fs::path path = Write("topics.bag", write);
  EXPECT_THAT(OpenError(path), AllOf(HasSubstr(path.string()), HasSubstr("/camera/rgb/image_color"),
                                     HasSubstr("/cam/color"), HasSubstr("--rgb-topic")));
  RosBagOptions options;
  options.rgb_topic = "/cam/color";
  EXPECT_EQ(OpenError(path, options), "");
}

TEST_F(RosBagTest, AnUnsupportedEncodingIsNamedWithItsTopicAndMessage) {
  RosBagWriteOptions write;
  write.max_frames = 2;
  const fs::path path = Write("encoding.bag", write);
  // The depth topic read as colour: its 32FC1 is no colour encoding.
  RosBagOptions options;
  options.rgb_topic = "/camera/depth/image";
  options.depth_topic = "/camera/rgb/image_color";
  EXPECT_THAT(OpenError(path, options),
              AllOf(HasSubstr(path.string()), HasSubstr("topic /camera/depth/image, message 1"),
                    HasSubstr("unsupported encoding '32FC1'"), HasSubstr("rgb8 or bgr8")));
}

TEST_F(RosBagTest, TruncatedAndForeignFilesAreNamedNotCrashedOn) {
  RosBagWriteOptions write;
  write.max_frames = 3;
  const fs::path path = Write("whole.bag", write);
  const std::uintmax_t size = fs::file_size(path);
  for (const std::uintmax_t keep : {size / 2, size - 100, std::uintmax_t{20}}) {
    SCOPED_TRACE(keep);
    const fs::path truncated = dir_ / "truncated.bag";
    fs::copy_file(path, truncated, fs::copy_options::overwrite_existing);
    fs::resize_file(truncated, keep);
    EXPECT_THAT(OpenError(truncated),
                AllOf(HasSubstr(truncated.string()), HasSubstr("truncated, or not a ROS1 bag")));
  }
  const fs::path text = dir_ / "text.bag";
  std::ofstream(text) << "not a bag\n";
  EXPECT_THAT(OpenError(text), AllOf(HasSubstr(text.string()), HasSubstr("not a ROS1 bag")));
  EXPECT_THAT(OpenError(dir_ / "missing.bag"), HasSubstr("no such bag file"));
}

TEST_F(RosBagTest, OptionsNameTheirInvalidField) {
  RosBagOptions options;
  options.depth_topic = options.rgb_topic;
  EXPECT_THROW(options.Check(), Error);
  RosBagWriteOptions write;
  write.depth_encoding = "mono8";
  EXPECT_THROW(WriteRosBag(*sequence_, kTumDepthFactor, dir_ / "x.bag", write), Error);
}

}  // namespace
}  // namespace noctua::io
