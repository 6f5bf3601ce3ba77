#pragma once

#include <opencv2/core.hpp>

namespace noctua::image {

// The standard deviation of a grey image's pixel noise, in grey levels, estimated from the image
// alone. The image is filtered with Immerkaer's 3x3 mask, the difference of two Laplacians, which
// cancels every grey ramp and leaves white noise of standard deviation 6 sigma; the median of its
// magnitude, not the mean, makes the few strong responses of edges and texture count like any
// other pixel, so a textured frame does not read as a noisy one. Pixels at 0 or 255 are left out
// (clipped, they carry no noise). Returns 0 for a frame with no usable pixel.
// Immerkaer, "Fast Noise Variance Estimation", CVIU 64(2), 1996.
double EstimateNoiseSigma(const cv::Mat& gray8u);

// EstimateNoiseSigma at the pixel scale and at half scale (cv::pyrDown), the latter referred back
// to the pixel scale as if the noise were white (pyrDown keeps 0.273 of white noise's deviation);
// the larger of the two. JPEG compression and demosaicing move a sensor's noise to coarser scales
// where the pixel-scale mask barely sees it. (What FAST meets is EstimateNoiseSigmaAtSpacing's.)
double EstimateNoiseSigmaAcrossScales(const cv::Mat& gray8u);

// The same mask with its taps `spacing` pixels apart (1: EstimateNoiseSigma): the noise of the
// comparisons a detector makes between pixels that far apart, as FAST's ring does at radius 3.
// Noise a camera leaves correlated (JPEG blocks, demosaicing) or that smoothing made so is larger
// there than a pixel-scale estimate and the white-noise rules built on it say.
double EstimateNoiseSigmaAtSpacing(const cv::Mat& gray8u, int spacing);

}  // namespace noctua::image
