#include "noctua/features/extractor_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "noctua/util/error.h"

namespace noctua::features {
namespace {

using ::testing::HasSubstr;

class ExtractorConfigTest : public ::testing::Test {
 protected:
  std::filesystem::path Write(const std::string& name, const std::string& text) {
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_extractor_config_" + std::to_string(::getpid()));
};

TEST_F(ExtractorConfigTest, ReadsOrbSlamSettingsWithOpenCvHeader) {
  const auto path = Write("orbslam.yaml",
                          "%YAML:1.0\n"
                          "Camera.fx: 517.3\n"
                          "ORBextractor.nFeatures: 1500\n"
                          "ORBextractor.scaleFactor: 1.25\n"
                          "ORBextractor.nLevels: 6\n"
                          "ORBextractor.iniThFAST: 25\n"
                          "ORBextractor.minThFAST: 5\n");
  const ExtractorOptions options = LoadExtractorOptions(path);
  EXPECT_EQ(options.fast.num_features, 1500);
  EXPECT_DOUBLE_EQ(options.fast.scale_factor, 1.25);
  EXPECT_EQ(options.fast.num_levels, 6);
  EXPECT_EQ(options.fast.initial_fast_threshold, 25);
  EXPECT_EQ(options.fast.min_fast_threshold, 5);
}

TEST_F(ExtractorConfigTest, ReadsTheExtractorSection) {
  const auto path = Write("noctua.yaml",
                          "extractor:\n"
                          "  enhancement: he\n"
                          "  clahe_clip_limit: 2.5\n"
                          "  edge_filter: false\n"
                          "  edge_radius_px: 3\n"
                          "  edge_fill: true\n"
                          "  nms_window: 5\n");
  const ExtractorOptions options = LoadExtractorOptions(path);
  EXPECT_EQ(options.enhancement.method, image::EnhancementMethod::kHistogramEqualization);
  EXPECT_DOUBLE_EQ(options.enhancement.clahe_clip_limit, 2.5);
  EXPECT_FALSE(options.edge_filter.enabled);
  EXPECT_DOUBLE_EQ(options.edge_filter.radius_px, 3.0);
  EXPECT_TRUE(options.edge_filter.fill_to_quota);
  EXPECT_FALSE(ExtractorOptions().edge_filter.fill_to_quota);
  EXPECT_EQ(options.nms_filter.window, 5);
}

TEST_F(ExtractorConfigTest, WrongTypesAndValuesAreRejectedNamingFileAndKey) {
  const auto wrong_type = Write("type.yaml", "ORBextractor.nFeatures: many\n");
  try {
    LoadExtractorOptions(wrong_type);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("type.yaml:1"));
    EXPECT_THAT(error.what(), HasSubstr("ORBextractor.nFeatures"));
  }
  const auto bad_value = Write("value.yaml", "extractor:\n  nms_window: 4\n");
  EXPECT_THROW(LoadExtractorOptions(bad_value), Error);
  const auto bad_method = Write("method.yaml", "extractor:\n  enhancement: gamma\n");
  EXPECT_THROW(LoadExtractorOptions(bad_method), Error);
  const auto malformed = Write("malformed.yaml", "extractor: [unclosed\n");
  EXPECT_THROW(LoadExtractorOptions(malformed), Error);
  EXPECT_THROW(LoadExtractorOptions(dir_ / "absent.yaml"), Error);
}

}  // namespace
}  // namespace noctua::features
