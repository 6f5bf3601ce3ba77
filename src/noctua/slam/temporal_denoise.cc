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
  const cv::Matx33d k(camera.fx(), 0.0, camera.cx(), 0.0, camera.fy(), camera.cy(), 0.0, 0.0, 1.0);
  return k * cv::Matx33d(rotation(cv::Rect(0, 0, 3, 3))) * k.inv();
}

}  // namespace

TemporalDenoiser::TemporalDenoiser(const geometry::PinholeCamera& camera,
                                   const TemporalDenoiseOptions& options)
    : camera_(camera), options_(options) {
  options_.Check();
  cv::Mat k_half = camera_.K().clone();
  k_half.convertTo(k_half, CV_64F);
  k_half.rowRange(0, 2) *= 0.5;
  odometry_ = cv::rgbd::RgbdOdometry::create(k_half);
  odometry_->setTransformType(cv::rgbd::Odometry::ROTATION);
}

void TemporalDenoiser::Reset() {
  history_.release();
  frames_.release();
  previous_half_.release();
  previous_depth_half_.release();
  last_motion_.release();
}

cv::Mat TemporalDenoiser::AlignToPrevious(const cv::Mat& lifted_half, const cv::Mat& depth_half) {
  cv::Mat motion;
  const cv::Mat no_mask;
  const bool found = odometry_->compute(lifted_half, depth_half, no_mask, previous_half_,
                                        previous_depth_half_, no_mask, motion, last_motion_);
  if (!found) return {};
  return motion;
}

cv::Mat TemporalDenoiser::Denoise(const cv::Mat& image, const cv::Mat& depth_m) {
  stats_ = {};
  const cv::Mat gray = image::ToGray8U(image);
  const double mean_grey = cv::mean(gray)[0];
  if (mean_grey >= options_.dark_mean_grey || mean_grey <= 0.0) {
    Reset();
    return gray;
  }
  stats_.noise_sigma = image::EstimateNoiseSigmaAcrossScales(gray);
  cv::Mat lifted_half;
  cv::pyrDown(gray, lifted_half);
  lifted_half.convertTo(lifted_half, CV_8U, kOdometryMeanGrey / mean_grey);
  const cv::Mat depth_half = HalfSizeDepth(depth_m);

  cv::Mat current;
  gray.convertTo(current, CV_32F);
  cv::Mat motion;
  if (!previous_half_.empty()) motion = AlignToPrevious(lifted_half, depth_half);
  previous_half_ = lifted_half;
  previous_depth_half_ = depth_half;
  last_motion_ = motion;
  if (motion.empty() || history_.empty()) {
    history_ = current;
    frames_ = cv::Mat::ones(current.size(), CV_32F);
    return gray;
  }

  // The history is resampled where each pixel was a frame ago (WARP_INVERSE_MAP: the homography
  // maps this frame's pixels into the previous frame).
  const cv::Matx33d homography = RotationHomography(camera_, motion);
  const int warp = cv::WARP_INVERSE_MAP;
  cv::Mat history, frames;
  cv::warpPerspective(history_, history, homography, current.size(), cv::INTER_LINEAR | warp,
                      cv::BORDER_CONSTANT, 0.0);
  cv::warpPerspective(frames_, frames, homography, current.size(), cv::INTER_NEAREST | warp,
                      cv::BORDER_CONSTANT, 0.0);
  cv::Mat difference = current - history;
  cv::blur(difference, difference, cv::Size(3, 3));

  // A 3x3 mean of differences of independent noise: the frame's σ² and the history's σ² / n
  // over 9 pixels.
  const double sigma = std::max(stats_.noise_sigma, 0.5);
  const double gate = options_.gate_sigmas * sigma / 3.0;
  const float max_frames = static_cast<float>(options_.max_frames);
  long kept = 0;
  double frame_sum = 0.0;
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
        ++kept;
      } else {
        n[u] = 1.0f;
      }
      frame_sum += n[u];
    }
  }
  history_ = current;
  frames_ = frames;
  const double pixels = static_cast<double>(current.total());
  stats_.applied = true;
  stats_.history_share = kept / pixels;
  stats_.mean_frames = frame_sum / pixels;
  cv::Mat denoised;
  current.convertTo(denoised, CV_8U);
  return denoised;
}

}  // namespace noctua::slam
