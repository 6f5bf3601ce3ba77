#include "noctua/io/camera_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "noctua/util/error.h"

namespace noctua::io {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kConfigDir = std::filesystem::path(NOCTUA_SOURCE_DIR) / "config";

class CameraConfigTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_camera_config_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string ErrorOf(const std::string& text) {
    const auto path = dir_ / "bad.yaml";
    std::ofstream(path) << text;
    try {
      ReadCameraConfig(path);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
};

TEST_F(CameraConfigTest, ReadsEveryPresetWithItsOrbSlamHeader) {
  const CameraConfig fr1 = ReadCameraConfig(kConfigDir / "tum_fr1.yaml");
  EXPECT_NEAR(fr1.intrinsics.fx, 517.3, 0.01);
  EXPECT_NEAR(fr1.intrinsics.cy, 255.3, 0.02);
  EXPECT_NEAR(fr1.distortion.k1, 0.2624, 1e-4);
  EXPECT_NEAR(fr1.distortion.k3, 1.1633, 1e-4);
  EXPECT_EQ(fr1.intrinsics.width, 640);
  EXPECT_DOUBLE_EQ(fr1.depth_factor, 5000.0);
  EXPECT_EQ(fr1.orb.num_features, 1000);
  EXPECT_TRUE(fr1.Camera().HasDistortion());

  const CameraConfig fr3 = ReadCameraConfig(kConfigDir / "tum_fr3.yaml");
  EXPECT_DOUBLE_EQ(fr3.intrinsics.fx, 535.4);
  EXPECT_DOUBLE_EQ(fr3.intrinsics.cy, 247.6);
  EXPECT_FALSE(fr3.Camera().HasDistortion());

  EXPECT_NEAR(ReadCameraConfig(kConfigDir / "tum_fr2.yaml").intrinsics.fx, 520.9, 0.01);
  const CameraConfig loris = ReadCameraConfig(kConfigDir / "openloris_d435i.yaml");
  EXPECT_EQ(loris.intrinsics.width, 848);
  EXPECT_DOUBLE_EQ(loris.depth_factor, 1000.0);
}

TEST_F(CameraConfigTest, AcceptsOrbSlam3CameraPrefix) {
  const auto path = dir_ / "orbslam3.yaml";
  std::ofstream(path) << "%YAML:1.0\nCamera1.fx: 500\nCamera1.fy: 501\nCamera1.cx: 320\n"
                         "Camera1.cy: 240\nCamera.width: 640\nCamera.height: 480\n"
                         "DepthMapFactor: 1000\n";
  const CameraConfig config = ReadCameraConfig(path);
  EXPECT_DOUBLE_EQ(config.intrinsics.fy, 501.0);
  EXPECT_FALSE(config.Camera().HasDistortion());
}

TEST_F(CameraConfigTest, BadSettingsNameFileKeyAndLine) {
  const std::string good_tail = "Camera.width: 640\nCamera.height: 480\n";
  EXPECT_THAT(ErrorOf("%YAML:1.0\nCamera.fy: 500\nCamera.cx: 320\nCamera.cy: 240\n" + good_tail +
                      "DepthMapFactor: 5000\n"),
              HasSubstr("bad.yaml: missing required setting 'Camera.fx'"));
  EXPECT_THAT(ErrorOf("Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 320\nCamera.cy: 240\n" +
                      good_tail + "DepthMapFactor: 0\n"),
              HasSubstr("DepthMapFactor must be a positive number"));
  EXPECT_THAT(ErrorOf("Camera.fx: 500\nCamera.fy: wide\nCamera.cx: 320\nCamera.cy: 240\n" +
                      good_tail + "DepthMapFactor: 5000\n"),
              HasSubstr("bad.yaml:2: setting 'Camera.fy' is not a number"));
  EXPECT_THAT(ErrorOf("Camera.fx: [500\n"), HasSubstr("bad.yaml:"));
  EXPECT_THAT(ErrorOf("- a list\n"), HasSubstr("expected a YAML map"));
  EXPECT_THROW(ReadCameraConfig(dir_ / "absent.yaml"), Error);
}

}  // namespace
}  // namespace noctua::io
