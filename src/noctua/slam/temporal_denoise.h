#pragma once

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "noctua/geometry/camera.h"
#include "noctua/image/enhancement.h"

namespace noctua::slam {

// Averaging of a dark frame with the frames before it, aligned by the camera's turn (docs/slam.md
// "Dark frames averaged along the motion"). In the dark the noise of one frame is the limit and a
// spatial filter buys its reduction with the corners it blurs; N aligned frames of a static scene
// divide the noise by about √N and keep every corner where it is. The turn between two frames
// comes from OpenCV's dense RGB-D odometry, at half resolution where the noise of the dark is
// already averaged down, and is a rotation only: from one frame to the next a hand-held camera
// moves millimetres, and a noisy frame cannot tell a small translation from a small turn (the
// full 6-DoF estimate traded centimetres of one for degrees of the other). A pixel whose history
// disagrees with it by more than the noise can explain (a moving person, the parallax of a near
// object, an edge misplaced) starts its history again from this frame.
struct TemporalDenoiseOptions {
  // Off by default: over 24 dark runs of tum_fr1_rpy_200 it lowered the mean ATE of `noctua` by
  // 5 % only (a third on the `kinect` model, none on the others) and on the dark Bonn crowd it
  // raised it (docs/slam.md).
  bool enabled = false;
  // Frames a pixel's running average may hold at most: the newest frame keeps a weight of at least
  // 1 / max_frames, so that an error of the alignment or a slow change fades within that many
  // frames. 4 divides the noise of a static pixel by √7 (an exponential average of weight 1/4).
  int max_frames = 4;
  // A pixel's history is kept while the 3x3 mean of its difference from the new frame is within
  // this many standard deviations of what the two frames' noise alone gives.
  double gate_sigmas = 3.0;
  // Frames with a mean grey at or above this are exposed well enough to need none (the rule of
  // the `noctua` extractor and of the detector's input).
  double dark_mean_grey = image::kUnderexposedMeanGrey;

  void Check() const;
};

// What Denoise did to the last frame.
struct TemporalDenoiseStats {
  bool applied = false;        // the frame was dark and had an aligned predecessor
  double noise_sigma = 0.0;    // of the input frame, grey levels
  double mean_frames = 1.0;    // frames averaged per pixel, on average over the image
  double history_share = 0.0;  // share of the pixels that kept their history
};

// Stateful: frames must come in order, from one camera. Not thread-safe.
class TemporalDenoiser {
 public:
  TemporalDenoiser(const geometry::PinholeCamera& camera, const TemporalDenoiseOptions& options);

  // Returns the frame to extract features from: for a dark frame, the grey (8-bit) running
  // average of the aligned frames before it and this one; otherwise the frame as it is, and the
  // history starts again. `depth_m` (CV_32F metres registered to `image`, 0 = no reading) is for
  // the odometry. Throws noctua::Error for depth of another size or type.
  cv::Mat Denoise(const cv::Mat& image, const cv::Mat& depth_m);
  const TemporalDenoiseStats& stats() const { return stats_; }

 private:
  // Rotation from this frame to the previous one (4x4 CV_64F, p_previous = T * p_this, no
  // translation), or empty when there is no previous frame or the odometry fails; keeps this
  // frame as the next one's previous.
  cv::Mat AlignToPrevious(const cv::Mat& gray, double mean_grey, const cv::Mat& depth_m);
  void Reset();

  geometry::PinholeCamera camera_;
  TemporalDenoiseOptions options_;
  cv::Ptr<cv::rgbd::RgbdOdometry> odometry_;
  cv::Mat history_;        // CV_32F running average of the aligned frames, grey levels
  cv::Mat frames_;         // CV_32F frames in each pixel's average
  cv::Mat previous_half_;  // previous frame for the odometry: lifted grey and depth, half size
  cv::Mat previous_depth_half_;
  cv::Mat last_rotation_;  // the odometry's last answer, the next one's starting point
  TemporalDenoiseStats stats_;
};

}  // namespace noctua::slam
