#pragma once

#include <opencv2/core.hpp>

#include "noctua/features/extractor_options.h"

namespace noctua::features {

// What noise-adaptive extraction decided for one frame, from the frame alone.
struct FrameConditioning {
  cv::Mat image;              // the grey frame FAST and rBRIEF see
  double mean_grey = 0.0;     // of the input frame
  double gain = 1.0;          // applied to the input
  double noise_sigma = 0.0;   // pixel noise after the gain, grey levels
  double blur_sigma = 0.0;    // Gaussian applied after the gain (0: none)
  double residual_sigma = 0;  // pixel noise FAST sees: after gain and blur
  PyramidFastOptions fast;    // the thresholds this frame's FAST uses
};

// Leaves a frame with a mean grey at or above options.target_mean_grey as it is (gain 1, no noise
// estimate, the given thresholds). Brightens a darker frame by one gain (the inverse of the missing
// light: FAST's and rBRIEF's tests compare grey values, a gain changes no comparison but the
// thresholds' meaning), measures the pixel noise that the gain amplified
// (image::EstimateNoiseSigma), smooths it when it is above what the thresholds can hold apart, and
// raises FAST's thresholds above the noise that is left, so that a corner is a structure of the
// scene and not a chance arrangement of noise.
FrameConditioning ConditionFrame(const cv::Mat& gray8u, const PyramidFastOptions& fast,
                                 const NoiseAdaptiveOptions& options);

}  // namespace noctua::features
