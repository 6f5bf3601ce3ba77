#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

namespace noctua::image {

// Mean grey that auto-exposure aims a frame at (sRGB's 18 % grey): a darker frame is one the camera
// could not expose, and the gain that brings it here is the inverse of the missing light.
inline constexpr double kAutoExposureMeanGrey = 118.0;
// Below this mean grey a frame is underexposed: normally lit TUM and Bonn frames have means of
// 90-160; a quarter of the 8-bit range, about half of what auto-exposure aims for, is a frame the
// camera could not expose. Chosen from that reasoning, not fitted to a run.
inline constexpr double kUnderexposedMeanGrey = 64.0;

enum class EnhancementMethod {
  kNone,
  kHistogramEqualization,  // global histogram equalisation (HE-ORB)
  kClahe,                  // contrast-limited adaptive histogram equalisation (the paper)
};

// Parses "none", "he", "clahe"; throws noctua::Error on anything else.
EnhancementMethod ParseEnhancementMethod(const std::string& name);
std::string ToString(EnhancementMethod method);

struct EnhancementOptions {
  EnhancementMethod method = EnhancementMethod::kClahe;
  // Defaults chosen by measurement (docs/enhancement.md, bench/enhancement_sweep): a low clip
  // limit on a coarse 4x4 grid gives the most correct matches on real low-light photos and on
  // darkened TUM frames; higher clips and finer grids amplify sensor noise into false corners.
  double clahe_clip_limit = 1.0;
  int clahe_tiles_x = 4;
  int clahe_tiles_y = 4;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Converts an 8-bit image with 1, 3 (BGR) or 4 (BGRA) channels to grey. Throws noctua::Error for
// empty images and for any other depth or channel count: callers convert 16-bit or float data
// themselves, because no single scaling is right for all of them.
cv::Mat ToGray8U(const cv::Mat& image);

// Applies one enhancement to 8-bit grey images. Holds the CLAHE object so repeated frames reuse it.
class Enhancer {
 public:
  explicit Enhancer(const EnhancementOptions& options);
  // Returns the enhanced grey image (the input itself, shared, for kNone).
  cv::Mat Apply(const cv::Mat& gray) const;
  const EnhancementOptions& options() const { return options_; }

 private:
  EnhancementOptions options_;
  cv::Ptr<cv::CLAHE> clahe_;
};

}  // namespace noctua::image
