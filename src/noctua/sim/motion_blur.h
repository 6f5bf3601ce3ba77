#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "noctua/geometry/camera.h"
#include "noctua/geometry/se3.h"
#include "noctua/io/trajectory.h"

namespace noctua::sim {

// The blur a longer exposure adds while the camera moves. `sample_from_frame` are camera poses
// spread evenly over the extra exposure, each as T_sample_frame (maps a point in the frame's
// camera coordinates into the sample's). Each pixel is reprojected with its depth (metres,
// CV_32F, 0 = none) into every sample's view and the image is averaged over the samples: what
// the sensor integrates while the camera moves (a static scene; lens distortion ignored, the
// blur is a few pixels). Pixels without depth take the median valid depth (kFallbackDepthM
// without any). An empty `depth_m` uses that fallback depth everywhere. With no samples the
// image is returned unchanged.
cv::Mat BlurAlongCameraMotion(const cv::Mat& image8u, const cv::Mat& depth_m,
                              const geometry::Intrinsics& intrinsics,
                              const std::vector<geometry::Pose>& sample_from_frame);

// A typical indoor RGB-D viewing distance, for pixels with no depth at all.
inline constexpr double kFallbackDepthM = 2.0;

// Samples per exposure: at most about one pixel of motion between samples for fr1's fastest
// turns (~1 deg per 20 ms at f = 517 px is ~9 px), so the average looks continuous.
inline constexpr int kBlurSamples = 16;

// The T_sample_frame poses for BlurAlongCameraMotion from a T_world_camera trajectory: `count`
// samples evenly over [t - duration/2, t + duration/2], the exposure centred on the frame's
// time stamp. Empty (no blur: the documented fallback) when the trajectory has no pose at t or
// at either end, or when duration is 0.
std::vector<geometry::Pose> ExposurePoses(const io::Trajectory& ground_truth, double t,
                                          double duration_s, int count = kBlurSamples);

}  // namespace noctua::sim
