#include "noctua/dynamic/dynamic_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

using ::testing::HasSubstr;

TEST(DynamicConfigFromYaml, AbsentSectionKeepsTheDefaults) {
  const DynamicConfig config = DynamicConfigFromYaml(YAML::Load("Camera.fx: 535.4\n"), "a.yaml");
  EXPECT_TRUE(config.model.empty());
  EXPECT_EQ(config.detector.input_width, DetectorOptions().input_width);
  EXPECT_EQ(config.mask.dynamic_levels, std::set<MotionLevel>{MotionLevel::kHigh});
}

TEST(DynamicConfigFromYaml, ReadsEveryKeyAndResolvesTheModelBesideTheFile) {
  const DynamicConfig config =
      DynamicConfigFromYaml(YAML::Load("dynamic:\n"
                                       "  model: models/yolo.onnx\n"
                                       "  input_width: 640\n"
                                       "  input_height: 480\n"
                                       "  score_threshold: 0.4\n"
                                       "  nms_iou: 0.5\n"
                                       "  shape: box\n"
                                       "  dilation_px: 2\n"
                                       "  depth_segment: false\n"
                                       "  object_half_depth_m: 0.5\n"
                                       "  motion_levels: {chair: high}\n"
                                       "  dynamic_levels: [high, medium]\n"),
                            "/settings/fr3.yaml");
  EXPECT_EQ(config.model, std::filesystem::path("/settings/models/yolo.onnx"));
  EXPECT_EQ(config.detector.input_width, 640);
  EXPECT_EQ(config.detector.input_height, 480);
  EXPECT_FLOAT_EQ(config.detector.score_threshold, 0.4f);
  EXPECT_FLOAT_EQ(config.detector.nms_iou, 0.5f);
  EXPECT_EQ(config.mask.shape, RegionShape::kBox);
  EXPECT_EQ(config.mask.dilation_px, 2);
  EXPECT_FALSE(config.mask.depth_segment);
  EXPECT_DOUBLE_EQ(config.mask.object_half_depth_m, 0.5);
  EXPECT_EQ(config.motion_levels.Level(CocoClassId("chair")), MotionLevel::kHigh);
  EXPECT_EQ(config.mask.dynamic_levels,
            (std::set<MotionLevel>{MotionLevel::kHigh, MotionLevel::kMedium}));
}

std::string ErrorOf(const std::string& yaml) {
  try {
    DynamicConfigFromYaml(YAML::Load(yaml), "s.yaml");
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(DynamicConfigFromYaml, BadValuesNameTheFileAndLine) {
  EXPECT_THAT(ErrorOf("dynamic:\n  shape: blob\n"), HasSubstr("s.yaml:2"));
  EXPECT_THAT(ErrorOf("dynamic:\n  modle: x.onnx\n"), HasSubstr("unknown key 'dynamic.modle'"));
  EXPECT_THAT(ErrorOf("dynamic:\n  input_width: wide\n"), HasSubstr("s.yaml:2"));
  EXPECT_THAT(ErrorOf("dynamic:\n  input_width: 300\n"), HasSubstr("multiple of 32"));
  EXPECT_THAT(ErrorOf("dynamic:\n  motion_levels: {desk: low}\n"), HasSubstr("not a COCO class"));
  EXPECT_THAT(ErrorOf("dynamic: 3\n"), HasSubstr("must be a map"));
}

}  // namespace
}  // namespace noctua::dynamic
