#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "noctua/image/enhancement.h"

namespace noctua::dynamic {

class Detector;

// How a dark frame is brightened before the detector sees it.
enum class DarkEnhancement {
  kGain,        // one gain that brings the mean grey to the target: the inverse of less light
  kGamma,       // one power curve that brings the mean grey to the target: lifts shadows more
  kSmoothGain,  // a Gaussian of smooth_sigma_px first, then the gain: the noise is not amplified
};
// Names as options write them ("gain", "gamma"), in one table.
const std::vector<std::pair<DarkEnhancement, std::string>>& DarkEnhancementNames();
std::string ToString(DarkEnhancement method);
// Throws noctua::Error naming the unknown name and listing the known ones.
DarkEnhancement ParseDarkEnhancement(const std::string& name);

// The detector's input in the dark. The detector was trained on well exposed photos (COCO): a
// frame the camera could not expose is brightened to a normal exposure's mean grey first.
struct DarkInputOptions {
  bool enabled = true;
  // A frame is dark when its mean grey is below this: an underexposed frame.
  double dark_mean_grey = image::kUnderexposedMeanGrey;
  // Mean grey the brightened input gets: mid-grey, where well exposed photos sit.
  double target_mean_grey = image::kAutoExposureMeanGrey;
  // Measured (docs/dynamic.md, bench/dark_detection): a gain alone amplifies the pixel noise of
  // small-pixel sensors until the detector misses people it finds without it; smoothing first
  // keeps recall at or above the unenhanced detector's for every sensor model.
  DarkEnhancement method = DarkEnhancement::kSmoothGain;
  // kSmoothGain's Gaussian, pixels of the frame: the detector sees a 640x480 frame at half scale,
  // where a person is 50 px or more tall, so 1.5 px at its scale removes pixel noise and keeps
  // shapes (of 1.5 and 3 frame pixels, 3 measured better on the noisiest model).
  double smooth_sigma_px = 3.0;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Mean grey over all colour samples of an 8-bit image.
double MeanGrey(const cv::Mat& image8u);

// Whether `image8u` is dark under `options` (enabled or not).
bool IsDark(const cv::Mat& image8u, const DarkInputOptions& options);

// The brightened image (same size and type): `options.method` bringing the mean grey to
// target_mean_grey. Alpha of BGRA is kept. A black frame is returned as it is.
cv::Mat BrightenForDetection(const cv::Mat& image8u, const DarkInputOptions& options);

// A detector that brightens dark frames (IsDark) before `inner` sees them; boxes and masks are in
// the same pixels, so nothing else changes. Normal frames go to `inner` untouched.
std::unique_ptr<Detector> MakeDarkAwareDetector(std::unique_ptr<Detector> inner,
                                                const DarkInputOptions& options);

}  // namespace noctua::dynamic
