#include "noctua/slam/temporal_denoise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "noctua/io/camera_config.h"
#include "noctua/io/dataset.h"
#include "noctua/sim/low_light.h"
#include "noctua/testing/shared_data.h"
#include "noctua/testing/test_camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

constexpr double kDarkMean = 30.0;
constexpr double kNoiseSigma = 4.0;
const cv::Rect kInterior(40, 40, 560, 400);  // clear of what shifts in from the border

// A dark textured scene seen by the test camera (500 px focal length) turned by `yaw_deg`: texture
// of blobs a few pixels wide, mean grey kDarkMean. The camera only turns, so the image moves by
// the same homography at every depth, and the depth (a ramp from 1 m at the left to 3 m at the
// right) can be anything that gives the odometry a scene that is not one plane.
cv::Mat DarkScene(double yaw_deg) {
  static const cv::Mat texture = [] {
    cv::Mat noise(600, 760, CV_32F);
    cv::RNG rng(7);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
    cv::GaussianBlur(noise, noise, cv::Size(), 2.0);
    cv::Scalar mean, deviation;
    cv::meanStdDev(noise, mean, deviation);
    return cv::Mat((noise - mean[0]) * (10.0 / deviation[0]) + kDarkMean);
  }();
  const cv::Matx33d k(500, 0, 320, 0, 500, 240, 0, 0, 1);
  cv::Mat rotation;
  cv::Rodrigues(cv::Vec3d(0.0, yaw_deg * CV_PI / 180.0, 0.0), rotation);
  const cv::Matx33d crop(1, 0, -60, 0, 1, -60, 0, 0, 1);
  cv::Mat view;
  cv::warpPerspective(texture, view, k * cv::Matx33d(rotation) * k.inv() * crop,
                      cv::Size(640, 480));
  return view;
}

cv::Mat DepthRamp() {
  cv::Mat depth(480, 640, CV_32F);
  for (int u = 0; u < depth.cols; ++u) depth.col(u).setTo(1.0 + 2.0 * u / depth.cols);
  return depth;
}

cv::Mat WithNoise(const cv::Mat& clean, cv::RNG& rng) {
  cv::Mat noise(clean.size(), CV_32F);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, kNoiseSigma);
  cv::Mat noisy;
  cv::Mat(clean + noise).convertTo(noisy, CV_8U);
  return noisy;
}

double RmsError(const cv::Mat& image8u, const cv::Mat& reference, const cv::Rect& region) {
  cv::Mat image;
  image8u.convertTo(image, CV_32F);
  cv::Mat reference32;
  reference.convertTo(reference32, CV_32F);
  const cv::Mat difference = image(region) - reference32(region);
  return std::sqrt(cv::mean(difference.mul(difference))[0]);
}

TEST(TemporalDenoiser, AveragesAStaticSceneAlongTheCameraMotion) {
  // The camera turns 0.15 degrees per frame: over a pixel, so an unaligned average would blur.
  TemporalDenoiser denoiser(testing::TestCamera(), {.enabled = true});
  const cv::Mat depth = DepthRamp();
  cv::RNG rng(11);
  cv::Mat clean, noisy, denoised;
  for (int i = 0; i < 8; ++i) {
    clean = DarkScene(0.15 * i);
    noisy = WithNoise(clean, rng);
    denoised = denoiser.Denoise(noisy, depth);
  }
  ASSERT_TRUE(denoiser.stats().applied);
  EXPECT_GT(denoiser.stats().mean_frames, 3.0);
  EXPECT_NEAR(denoiser.stats().noise_sigma, kNoiseSigma, 1.0);
  const double single = RmsError(noisy, clean, kInterior);
  const double averaged = RmsError(denoised, clean, kInterior);
  EXPECT_NEAR(single, kNoiseSigma, 0.5);
  // Four frames in an exponential average of weight 1/4 leave σ / √7 of white noise, plus the
  // resampling's and the rounding's share.
  EXPECT_LT(averaged, 0.7 * single) << "single " << single << ", averaged " << averaged;
}

TEST(TemporalDenoiser, KeepsNoHistoryWhereSomethingMoved) {
  TemporalDenoiser denoiser(testing::TestCamera(), {.enabled = true});
  const cv::Mat depth = DepthRamp();
  cv::RNG rng(5);
  cv::Mat clean, denoised;
  const cv::Rect square_at_end(300, 200, 60, 60);
  for (int i = 0; i < 6; ++i) {
    clean = DarkScene(0.0);
    // A bright square that jumps 40 px per frame over the static wall.
    clean(square_at_end - cv::Point(40 * (5 - i), 0)).setTo(kDarkMean + 40.0);
    denoised = denoiser.Denoise(WithNoise(clean, rng), depth);
  }
  ASSERT_TRUE(denoiser.stats().applied);
  // No ghost: the square is as bright as it is, and where it was a frame ago is the wall again,
  // with this frame's noise (a quarter of the square's history would be 10 grey levels off).
  const cv::Rect inner_square(square_at_end.x + 3, square_at_end.y + 3, 54, 54);
  EXPECT_NEAR(cv::mean(denoised(inner_square))[0], kDarkMean + 40.0, 2.0);
  const cv::Rect inner_before = inner_square - cv::Point(40, 0) + cv::Point(-20, 0);
  EXPECT_LT(RmsError(denoised, clean, inner_before), 1.2 * kNoiseSigma);
}

TEST(TemporalDenoiser, LeavesWellExposedFramesAsTheyAre) {
  TemporalDenoiser denoiser(testing::TestCamera(), {.enabled = true});
  const cv::Mat depth = DepthRamp();
  cv::RNG rng(3);
  for (int i = 0; i < 3; ++i) {
    cv::Mat bright;
    WithNoise(DarkScene(0.1 * i) + 100.0, rng).copyTo(bright);
    const cv::Mat out = denoiser.Denoise(bright, depth);
    EXPECT_FALSE(denoiser.stats().applied);
    EXPECT_EQ(cv::norm(out, bright, cv::NORM_INF), 0.0);
  }
}

TEST(TemporalDenoiser, RefusesDepthThatDoesNotFitTheFrame) {
  TemporalDenoiser denoiser(testing::TestCamera(), {.enabled = true});
  cv::Mat frame;
  DarkScene(0.0).convertTo(frame, CV_8U);
  EXPECT_THROW(denoiser.Denoise(frame, cv::Mat(240, 320, CV_32F, cv::Scalar(1.0))), Error);
  EXPECT_THROW(denoiser.Denoise(frame, cv::Mat(480, 640, CV_16U, cv::Scalar(5000))), Error);
  EXPECT_NO_THROW(denoiser.Denoise(frame, DepthRamp()));
}

TEST(TemporalDenoiser, RefusesInvalidOptions) {
  EXPECT_THROW(TemporalDenoiser(testing::TestCamera(), {.enabled = true, .max_frames = 0}), Error);
  EXPECT_THROW(TemporalDenoiser(testing::TestCamera(), {.enabled = true, .gate_sigmas = 0.0}),
               Error);
}

// Real frames and real motion: the first frames of tum_fr1_rpy_200 (a hand-held camera turning)
// darkened to 15 % by the `kinect` sensor model. Against the model's expected (noise-free) output
// of the clean frame, the average of the aligned frames is closer than the frame alone.
TEST(TemporalDenoiser, ReducesTheNoiseOfRealDarkFrames) {
  const std::filesystem::path config =
      std::filesystem::path(NOCTUA_SOURCE_DIR) / "config" / "tum_fr1.yaml";
  const io::CameraConfig camera = io::ReadCameraConfig(config);
  const io::Sequence sequence = io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200");
  const sim::LowLightSimulator dark(sim::SensorModelByName("kinect"), 0.15);
  cv::Mat expected_of_value(1, 256, CV_32F);
  for (int v = 0; v < 256; ++v) {
    expected_of_value.at<float>(v) = static_cast<float>(dark.ExpectedOutput(v).mean);
  }
  TemporalDenoiser denoiser(camera.Camera(), {.enabled = true});
  cv::RNG rng(1);
  double single = 0.0, averaged = 0.0;
  for (int i = 0; i < 6; ++i) {
    const io::FrameImages images = sequence.Load(sequence.frame(i), camera.depth_factor);
    cv::Mat gray;
    cv::cvtColor(images.bgr, gray, cv::COLOR_BGR2GRAY);
    const cv::Mat noisy = dark.Apply(gray, rng);
    const cv::Mat denoised = denoiser.Denoise(noisy, images.depth_m);
    if (i < 3) continue;  // the history fills up
    ASSERT_TRUE(denoiser.stats().applied);
    cv::Mat expected;
    cv::LUT(gray, expected_of_value, expected);
    single += RmsError(noisy, expected, kInterior);
    averaged += RmsError(denoised, expected, kInterior);
  }
  EXPECT_LT(averaged, 0.8 * single) << "single " << single / 3 << ", averaged " << averaged / 3;
}

}  // namespace
}  // namespace noctua::slam
