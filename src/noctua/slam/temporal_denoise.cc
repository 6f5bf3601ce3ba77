#include "noctua/slam/temporal_denoise.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/image/enhancement.h"
#include "noctua/image/noise.h"
#include "noctua/util/error.h"

namespace noctua::slam {

void TemporalDenoiseOptions::Check() const {
  if (max_frames < 1) throw Error("temporal_denoise: max_frames must be at least 1");
  if (!(gate_sigmas > 0.0)) throw Error("temporal_denoise: gate_sigmas must be positive");
  if (!(dark_mean_grey > 0.0 && dark_mean_grey <= 255.0)) {
    throw Error("temporal_denoise: dark_mean_grey must be in (0, 255]");
  }
}

namespace {

// The odometry's images are lifted to this mean grey, so that its gradient thresholds (set for a
// normally exposed frame) mean the same in the dark.
constexpr double kOdometryMeanGrey = 128.0;

cv::Mat HalfSizeDepth(const cv::Mat& depth_m) {
  cv::Mat half;
  cv::resize(depth_m, half, depth_m.size() / 2, 0, 0, cv::INTER_NEAREST);
  return half;
}

// The homography that takes a pixel of this frame to where it was in the previous one when the
// camera turned by `rotation` (p_previous = R p_this): K R K^-1, the same at every depth.
cv::Matx33d RotationHomography(const geometry::PinholeCamera& camera, const cv::Mat& rotation) {
  const cv::Matx33d k = camera.K();
  return k * cv::Matx33d(rotation(cv::Rect(0, 0, 3, 3))) * k.inv();
}

struct FusionCounts {
  long kept = 0;           // pixels that kept their history
  double frame_sum = 0.0;  // of the frames in each pixel's average
};

// Folds `current` (CV_32F) into its warped `history` where the 3x3 mean `difference` is within
// what the noise explains: the frame's σ² and the history's σ² / n over 9 pixels. `frames` holds
// each pixel's count of averaged frames (0: no history) and is updated with `current`.
FusionCounts FuseWithHistory(const cv::Mat& history, const cv::Mat& difference, double noise_sigma,
                             const TemporalDenoiseOptions& options, cv::Mat& current,
                             cv::Mat& frames) {
  const double gate = options.gate_sigmas * std::max(noise_sigma, 0.5) / 3.0;
  const float max_frames = static_cast<float>(options.max_frames);
  FusionCounts counts;
  for (int v = 0; v < current.rows; ++v) {
    float* out = current.ptr<float>(v);
    float* n = frames.ptr<float>(v);
    const float* h = history.ptr<float>(v);
    const float* d = difference.ptr<float>(v);
    for (int u = 0; u < current.cols; ++u) {
      const float held = n[u];
      const double limit = gate * std::sqrt(1.0 + 1.0 / std::max(held, 1.0f));
      if (held >= 1.0f && std::abs(d[u]) <= limit) {
        const float weight = std::min(held, max_frames - 1.0f);
        out[u] = (out[u] + weight * h[u]) / (weight + 1.0f);
        n[u] = weight + 1.0f;
        ++counts.kept;
      } else {
        n[u] = 1.0f;
      }
      counts.frame_sum += n[u];
    }
  }
  return counts;
}

}  // namespace

TemporalDenoiser::TemporalDenoiser(const geometry::PinholeCamera& camera,
                                   const TemporalDenoiseOptions& options)
    : camera_(camera), options_(options) {
  options_.Check();
  cv::Mat k_half = camera_.K();  // a fresh CV_64F matrix
  k_half.rowRange(0, 2) *= 0.5;
  odometry_ = cv::rgbd::RgbdOdometry::create(k_half);
  odometry_->setTransformType(cv::rgbd::Odometry::ROTATION);
}

void TemporalDenoiser::Reset() {
  history_.release();
  frames_.release();
  previous_half_.release();
  previous_depth_half_.release();
  last_rotation_.release();
}

cv::Mat TemporalDenoiser::AlignToPrevious(const cv::Mat& gray, double mean_grey,
                                          const cv::Mat& depth_m) {
  cv::Mat lifted_half;
  cv::pyrDown(gray, lifted_half);
  lifted_half.convertTo(lifted_half, CV_8U, kOdometryMeanGrey / mean_grey);
  const cv::Mat depth_half = HalfSizeDepth(depth_m);
  cv::Mat rotation;
  if (!previous_half_.empty()) {
    const cv::Mat no_mask;
    const bool found = odometry_->compute(lifted_half, depth_half, no_mask, previous_half_,
                                          previous_depth_half_, no_mask, rotation, last_rotation_);
    if (!found) rotation.release();
  }
  previous_half_ = lifted_half;
  previous_depth_half_ = depth_half;
  last_rotation_ = rotation;
  return rotation;
}

cv::Mat TemporalDenoiser::Denoise(const cv::Mat& image, const cv::Mat& depth_m) {
  stats_ = {};
  if (depth_m.size() != image.size() || depth_m.type() != CV_32FC1) {
    throw Error("temporal_denoise: depth must be CV_32F metres of the image's size");
  }
  const cv::Mat gray = image::ToGray8U(image);
  const double mean_grey = cv::mean(gray)[0];
  if (mean_grey >= options_.dark_mean_grey || mean_grey <= 0.0) {
    Reset();
    return image;  // as it came, colour included (a detector in line sees it)
  }
  stats_.noise_sigma = image::EstimateNoiseSigmaAcrossScales(gray);
  const cv::Mat rotation = AlignToPrevious(gray, mean_grey, depth_m);
  cv::Mat current;
  gray.convertTo(current, CV_32F);
  if (rotation.empty() || history_.empty()) {
    history_ = current;
    frames_ = cv::Mat::ones(current.size(), CV_32F);
    return gray;
  }

  // The history is resampled where each pixel was a frame ago (WARP_INVERSE_MAP: the homography
  // maps this frame's pixels into the previous frame).
  const cv::Matx33d homography = RotationHomography(camera_, rotation);
  const int warp = cv::WARP_INVERSE_MAP;
  cv::Mat history, frames;
  cv::warpPerspective(history_, history, homography, current.size(), cv::INTER_LINEAR | warp,
                      cv::BORDER_CONSTANT, 0.0);
  cv::warpPerspective(frames_, frames, homography, current.size(), cv::INTER_NEAREST | warp,
                      cv::BORDER_CONSTANT, 0.0);
  cv::Mat difference = current - history;
  cv::blur(difference, difference, cv::Size(3, 3));

  const FusionCounts counts =
      FuseWithHistory(history, difference, stats_.noise_sigma, options_, current, frames);
  history_ = current;
  frames_ = frames;
  const double pixels = static_cast<double>(current.total());
  stats_.applied = true;
  stats_.history_share = static_cast<double>(counts.kept) / pixels;
  stats_.mean_frames = counts.frame_sum / pixels;
  cv::Mat denoised;
  current.convertTo(denoised, CV_8U);
  return denoised;
}

}  // namespace noctua::slam
