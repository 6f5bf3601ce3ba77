#include "noctua/sim/motion_blur.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/util/error.h"

namespace noctua::sim {

namespace {

// Depth with every hole filled by the median valid depth.
cv::Mat FilledDepth(const cv::Mat& depth_m, cv::Size size) {
  if (depth_m.empty()) return cv::Mat(size, CV_32F, cv::Scalar(kFallbackDepthM));
  if (depth_m.type() != CV_32F || depth_m.size() != size) {
    throw Error("motion blur needs a CV_32F depth map of the image's size");
  }
  std::vector<float> valid;
  valid.reserve(depth_m.total());
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* row = depth_m.ptr<float>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      if (row[x] > 0.0f && std::isfinite(row[x])) valid.push_back(row[x]);
    }
  }
  float fill = static_cast<float>(kFallbackDepthM);
  if (!valid.empty()) {
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    fill = valid[valid.size() / 2];
  }
  cv::Mat filled = depth_m.clone();
  filled.setTo(fill, ~(depth_m > 0.0f));
  return filled;
}

// The image seen from one sample pose: I_s(p) ~ I(p - flow(p)), flow(p) the reprojection of
// pixel p (at its depth) into the sample's view minus p. The first-order inverse holds because
// the flow varies little over a pixel's own displacement.
void AccumulateSample(const cv::Mat& image, const cv::Mat& depth, const geometry::Intrinsics& k,
                      const geometry::Pose& sample_from_frame, cv::Mat& sum) {
  cv::Mat map_x(image.size(), CV_32F), map_y(image.size(), CV_32F);
  const Eigen::Matrix3d rotation = sample_from_frame.linear();
  const Eigen::Vector3d translation = sample_from_frame.translation();
  for (int y = 0; y < image.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    float* mx = map_x.ptr<float>(y);
    float* my = map_y.ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      const Eigen::Vector3d point((x - k.cx) / k.fx * d[x], (y - k.cy) / k.fy * d[x], d[x]);
      const Eigen::Vector3d moved = rotation * point + translation;
      double u = x, v = y;
      if (moved.z() > 1e-6) {
        u = k.fx * moved.x() / moved.z() + k.cx;
        v = k.fy * moved.y() / moved.z() + k.cy;
      }
      mx[x] = static_cast<float>(2.0 * x - u);
      my[x] = static_cast<float>(2.0 * y - v);
    }
  }
  cv::Mat warped;
  cv::remap(image, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  cv::accumulate(warped, sum);
}

}  // namespace

cv::Mat BlurAlongCameraMotion(const cv::Mat& image8u, const cv::Mat& depth_m,
                              const geometry::Intrinsics& intrinsics,
                              const std::vector<geometry::Pose>& sample_from_frame) {
  if (image8u.empty() || image8u.depth() != CV_8U) {
    throw Error("motion blur needs an 8-bit image");
  }
  if (sample_from_frame.empty()) return image8u.clone();
  CheckOption(intrinsics.fx > 0.0 && intrinsics.fy > 0.0, "motion blur needs focal lengths");
  const cv::Mat depth = FilledDepth(depth_m, image8u.size());
  cv::Mat sum(image8u.size(), CV_MAKETYPE(CV_32F, image8u.channels()), cv::Scalar::all(0));
  for (const geometry::Pose& pose : sample_from_frame) {
    AccumulateSample(image8u, depth, intrinsics, pose, sum);
  }
  cv::Mat out;
  sum.convertTo(out, image8u.type(), 1.0 / static_cast<double>(sample_from_frame.size()));
  return out;
}

std::vector<geometry::Pose> ExposurePoses(const io::Trajectory& ground_truth, double t,
                                          double duration_s, int count) {
  CheckOption(count >= 2, "motion blur needs at least 2 samples per exposure");
  std::vector<geometry::Pose> poses;
  if (!(duration_s > 0.0)) return poses;
  const std::optional<geometry::Pose> world_from_frame = ground_truth.Interpolate(t);
  if (!world_from_frame) return poses;
  for (int i = 0; i < count; ++i) {
    const double s = t - 0.5 * duration_s + duration_s * i / (count - 1.0);
    const std::optional<geometry::Pose> world_from_sample = ground_truth.Interpolate(s);
    if (!world_from_sample) return {};
    poses.push_back(world_from_sample->inverse() * *world_from_frame);
  }
  return poses;
}

}  // namespace noctua::sim
