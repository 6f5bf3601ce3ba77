#pragma once

#include <string>
#include <vector>

namespace noctua::sim {

// The camera that "takes" a darker picture of a normally lit frame (see LowLightSimulator for
// how the numbers are used). A normally lit 8-bit frame is read as this camera's normal-light
// exposure: the linear irradiance it collected, its own motion blur over `exposure_s` included.
//
// Levels: "15 %" always means the expected mean grey of the output is 15 % of the input's mean
// grey (noise and clipping included; BrightnessForMeanRatio finds the light factor for it). No
// gain is applied: a dark frame stays dark, as a real camera's does at its longest exposure.
struct SensorModel {
  std::string name = "custom";
  std::string description;
  // Response curve: 8-bit value = 255 * (electrons / full well)^(1 / gamma).
  double gamma = 2.2;
  double full_well_electrons = 6000.0;
  // Temporal noise: Poisson shot noise of the photo-electrons (off only for the noiseless
  // reference) and Gaussian read noise.
  bool shot_noise = true;
  double read_noise_electrons = 3.0;
  // Dark current over the exposure. Its mean is removed (the optical-black clamp of real
  // sensors); its shot noise stays.
  double dark_current_e_per_s = 0.0;
  // Fixed-pattern noise, the same in every frame of a sequence: per-pixel offset (DSNU, rms
  // electrons) and per-pixel gain (PRNU, relative rms).
  double dsnu_electrons = 0.0;
  double prnu = 0.0;
  // Row noise: one Gaussian offset per row and frame (rms electrons), the banding of cheap
  // rolling-shutter readouts.
  double row_noise_electrons = 0.0;
  // JPEG quality of the output stream (0: none, 1-100: compressed as webcams do).
  int jpeg_quality = 0;
  // Exposure at normal light, and the longest one the camera takes. A frame darker than normal
  // is one the auto-exposure could not brighten, so it was taken at `max_exposure_s`; the extra
  // exposure (max - normal) adds motion blur along the camera's motion.
  double exposure_s = 0.010;
  double max_exposure_s = 0.030;

  // Throws noctua::Error naming the model and the first invalid field.
  void Check() const;

  // Exposure time of a frame at `level` (mean grey ratio, (0, 1]): exposure_s at 1, else
  // max_exposure_s.
  double ExposureForLevel(double level) const;
  // The exposure a dark frame adds to the input's (and so the extra motion blur), seconds.
  double ExtraExposureForLevel(double level) const;
};

// The family of sensor models, in one table: its single definition. The first entries span
// small noisy pixels to large quiet ones; "noiseless" (the tone curve and 8-bit rounding only,
// i.e. a plain scaling of grey values) is the reference for tests that isolate brightness.
const std::vector<SensorModel>& SensorModels();

// Throws noctua::Error naming the unknown name and listing the known ones.
const SensorModel& SensorModelByName(const std::string& name);

// "webcam, kinect, ..." for help texts and errors.
std::string SensorModelNames();

// The named model with a user's overrides: full well (electrons; <= 0 keeps the model's), read
// noise (electrons rms; < 0 keeps the model's) and longest exposure (seconds, at least the
// normal-light one; <= 0 keeps the model's: a camera told to expose for less in the dark takes a
// darker, sharper frame). The name says when anything was overridden.
SensorModel SensorModelWithOverrides(const std::string& name, double full_well_electrons,
                                     double read_noise_electrons, double max_exposure_s = 0.0);

// The model `noctua simulate` and the demo use unless told otherwise.
inline constexpr const char* kDefaultSensorModel = "kinect";

// A Markdown table of every model (name and parameters), for --list-sensors and the docs.
std::string SensorModelTable();

}  // namespace noctua::sim
