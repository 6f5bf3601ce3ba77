#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>

#include "noctua/sim/sensor_model.h"

namespace noctua::sim {

// One darker exposure under a SensorModel: `brightness` is the factor on collected light
// (0 < brightness <= 1); below 1 the frame is taken at the model's longest exposure.
//
//   linear  x = (v / 255) ^ gamma                          v: original 8-bit value
//   signal  e = Poisson(brightness * x * full_well) * (1 + PRNU(p)) + DSNU(p) + row(y)
//               + Normal(0, read_noise^2 + dark_current * exposure)     [electrons]
//   output  v' = round(255 * clamp(e / full_well, 0, 1) ^ (1 / gamma)), then JPEG if the model
//               has it
//
// PRNU and DSNU are fixed patterns (seeded by the model's name and the image size, the same in
// every frame); row(y) is drawn anew per row and frame. Motion blur is not applied here (see
// motion_blur.h): it needs the camera's motion.
class LowLightSimulator {
 public:
  LowLightSimulator(const SensorModel& model, double brightness);

  // Darkens an 8-bit grey, BGR or BGRA frame (each colour channel as its own sensor pixel; alpha
  // is kept). The noise comes from `rng`, so a fixed seed reproduces a sequence.
  cv::Mat Apply(const cv::Mat& image8u, cv::RNG& rng) const;

  // Mean and variance over a flat patch of the 8-bit output for an original value, computed from
  // the model (Poisson sum over electron counts, the Gaussian terms - read noise, dark-current
  // shot noise, row noise and the fixed patterns - integrated over each quantisation bin). JPEG
  // is not part of it: these are the sensor's moments before compression.
  struct Moments {
    double mean = 0.0;
    double variance = 0.0;
  };
  Moments ExpectedOutput(int value8u) const;

  // Expected linear signal in electrons of an 8-bit value, and its variance under the model
  // (every term, over a flat patch).
  double ExpectedElectrons(double value8u) const;
  double ElectronVariance(double value8u) const;
  // Variance of the Gaussian terms at a signal of `electrons`.
  double GaussianVariance(double electrons) const;
  double exposure_s() const { return exposure_s_; }

  const SensorModel& model() const { return model_; }
  double brightness() const { return brightness_; }

 private:
  SensorModel model_;
  double brightness_;
  double exposure_s_;
  void ComputeMoments();
  cv::Mat FixedPattern(cv::Size size, int channels, double sigma, std::uint64_t salt) const;

  std::array<Moments, 256> moments_;
};

// The light factor whose expected output (noise included) has `mean_ratio` times the mean grey of
// `reference` (8-bit grey or colour). Levels are named by this ratio: "15%" makes a frame of mean
// 156 into one of mean ~23. Throws noctua::Error when the ratio is outside (0, 1] or the frame is
// black.
double BrightnessForMeanRatio(const cv::Mat& reference, double mean_ratio,
                              const SensorModel& model);

// The simulator whose output of `reference` has `level` times its mean grey.
LowLightSimulator SimulatorForLevel(const cv::Mat& reference, double level,
                                    const SensorModel& model);

// One frame darkened to `level` (mean grey ratio) by `model`, calibrated on the frame itself,
// noise from `seed`, without motion blur (a still camera). Level 1 returns the frame as it is:
// "100 %" is the input, whose own noise is real. The one way a single frame is darkened in
// noctua (demo, tests, benchmarks, `noctua slam --brightness`).
cv::Mat DarkenToLevel(const cv::Mat& image, double level, const SensorModel& model,
                      std::uint64_t seed);

// The same for the frames of a sequence, as a transform of (frame index, image): the light
// factor calibrated once on `reference` (a fixed light, as SimulateSequence does), frame k's noise
// from seed + k. Empty at level 1 (the frames as they are). Safe to call from several threads.
using FrameTransform = std::function<cv::Mat(int, const cv::Mat&)>;
FrameTransform SequenceDarkener(const cv::Mat& reference, double level, const SensorModel& model,
                                std::uint64_t seed);

}  // namespace noctua::sim
