#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>

namespace noctua::sim {

// The camera that "takes" the darker picture. A normally lit 8-bit frame is read as the linear
// irradiance the original exposure collected; the darker exposure collects `brightness` times as
// many photo-electrons, counted with Poisson shot noise, plus Gaussian read noise, and is written
// back through the same gamma without any gain (a dark frame stays dark, as real photos do).
//
//   linear  x = (v / 255) ^ gamma                          v: original 8-bit value
//   signal  e ~ Poisson(brightness * x * full_well) + Normal(0, read_noise^2)   [electrons]
//   output  v' = round(255 * clamp(e / full_well, 0, 1) ^ (1 / gamma))
//
// Defaults: gamma 2.2 (the usual display gamma an 8-bit camera frame is encoded with); a full
// well of 6000 e- and 3 e- rms read noise, typical of the small-pixel CMOS sensors in RGB-D
// cameras (the fr1 Kinect has ~3 um pixels). At the "15%" level a mid-grey pixel then collects
// ~20 e-, an SNR near 4, about as noisy as the real LOL photos in data/lowlight.
struct SensorModel {
  double gamma = 2.2;
  double full_well_electrons = 6000.0;
  double read_noise_electrons = 3.0;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// One darker exposure: `brightness` is the factor on collected light (0 < brightness <= 1).
class LowLightSimulator {
 public:
  LowLightSimulator(const SensorModel& model, double brightness);

  // Darkens an 8-bit grey, BGR or BGRA frame (each colour channel as its own sensor pixel; alpha
  // is kept). The noise comes from `rng`, so a fixed seed reproduces a sequence.
  cv::Mat Apply(const cv::Mat& image8u, cv::RNG& rng) const;

  // Mean and variance of the 8-bit output for an original value, computed from the model
  // (Poisson sum over electron counts, read noise integrated over each quantisation bin).
  struct Moments {
    double mean = 0.0;
    double variance = 0.0;
  };
  Moments ExpectedOutput(int value8u) const;

  // Expected linear signal in electrons of an 8-bit value, and its variance under the model.
  double ExpectedElectrons(double value8u) const;
  double ElectronVariance(double value8u) const;

  const SensorModel& model() const { return model_; }
  double brightness() const { return brightness_; }

 private:
  SensorModel model_;
  double brightness_;
  void ComputeMoments();

  std::array<Moments, 256> moments_;
};

// The light factor whose expected output (noise included) has `mean_ratio` times the mean grey of
// `reference` (8-bit grey or colour). Levels are named by this ratio: "15%" makes a frame of mean
// 156 into one of mean ~23. Throws noctua::Error when the ratio is outside (0, 1] or the frame is
// black.
double BrightnessForMeanRatio(const cv::Mat& reference, double mean_ratio,
                              const SensorModel& model);

}  // namespace noctua::sim
