#include "noctua/io/image_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

using ::testing::HasSubstr;

class ImageFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_image_file_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
};

template <typename Fn>
std::string ErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST_F(ImageFileTest, ReadsRealTumFrames) {
  const auto rgb_path = noctua::testing::Fr1RgbPaths(1).front();
  const cv::Mat rgb = ReadImage8U(rgb_path);
  EXPECT_EQ(rgb.size(), cv::Size(640, 480));
  EXPECT_EQ(rgb.type(), CV_8UC3);
  const auto depth_path = rgb_path.parent_path().parent_path() / "depth" / "1305031229.528784.png";
  const cv::Mat depth = ReadDepth16U(depth_path);
  EXPECT_EQ(depth.type(), CV_16UC1);
}

TEST_F(ImageFileTest, MissingFileNamesTheFile) {
  const auto path = dir_ / "absent.png";
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(path); }), HasSubstr("absent.png: no such file"));
}

TEST_F(ImageFileTest, CorruptAndTruncatedFilesAreRefused) {
  const auto garbage = dir_ / "garbage.png";
  std::ofstream(garbage) << "this is not a png";
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(garbage); }), HasSubstr("cannot decode"));

  const auto full = dir_ / "full.png";
  cv::imwrite(full.string(), cv::Mat(64, 64, CV_8UC1, cv::Scalar(7)));
  std::ifstream in(full, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const auto truncated = dir_ / "truncated.png";
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(truncated); }), HasSubstr("truncated.png"));
}

TEST_F(ImageFileTest, EightBitDepthIsRefusedAndSixteenBitColourIsRefused) {
  const auto depth8 = dir_ / "depth8.png";
  cv::imwrite(depth8.string(), cv::Mat(8, 8, CV_8UC1, cv::Scalar(3)));
  EXPECT_THAT(ErrorOf([&] { ReadDepth16U(depth8); }), HasSubstr("expected a 16-bit"));

  const auto colour16 = dir_ / "colour16.png";
  cv::imwrite(colour16.string(), cv::Mat(8, 8, CV_16UC1, cv::Scalar(3000)));
  EXPECT_THAT(ErrorOf([&] { ReadImage8U(colour16); }), HasSubstr("expected an 8-bit image"));
}

}  // namespace
}  // namespace noctua::io
