#include "noctua/sim/sensor_model.h"

#include <cmath>
#include <opencv2/core.hpp>

#include "noctua/util/error.h"

namespace noctua::sim {

namespace {

// Positional initialisation below: name, description, gamma, full well, shot noise, read
// noise, dark current, DSNU, PRNU, row noise, JPEG quality, exposure, max exposure.
SensorModel Make(const char* name, const char* description, double gamma, double full_well,
                 double read_noise, double dark_current, double dsnu, double prnu, double row_noise,
                 int jpeg_quality, double exposure_s, double max_exposure_s) {
  SensorModel m;
  m.name = name;
  m.description = description;
  m.gamma = gamma;
  m.full_well_electrons = full_well;
  m.read_noise_electrons = read_noise;
  m.dark_current_e_per_s = dark_current;
  m.dsnu_electrons = dsnu;
  m.prnu = prnu;
  m.row_noise_electrons = row_noise;
  m.jpeg_quality = jpeg_quality;
  m.exposure_s = exposure_s;
  m.max_exposure_s = max_exposure_s;
  return m;
}

std::vector<SensorModel> BuildModels() {
  // Figures are typical of each class of sensor (data sheets and EMVA 1288 reports of similar
  // parts), not of one product; the spread between them is the point.
  std::vector<SensorModel> models = {
      Make("webcam",
           "small-pixel phone/webcam sensor (~1.4 um), rolling shutter, JPEG stream: few "
           "electrons, warm and banded",
           2.2, 3000.0, 4.0, 50.0, 2.0, 0.015, 1.5, 75, 0.010, 0.033),
      Make("kinect",
           "Kinect/Xtion-class RGB sensor (~2.8 um), rolling shutter, raw frames (noctua's "
           "earlier single model, with dark current and fixed pattern added)",
           2.2, 6000.0, 3.0, 20.0, 1.0, 0.010, 1.0, 0, 0.010, 0.030),
      Make("d435",
           "RealSense D435-like global-shutter sensor (~3 um): short exposures, higher read noise "
           "of the global-shutter readout, flatter response",
           1.8, 10000.0, 8.0, 10.0, 2.0, 0.010, 0.5, 0, 0.004, 0.016),
      Make("large-pixel",
           "large-pixel low-noise sensor (~6 um, machine-vision class): deep well, ~1.5 e- "
           "read noise, steeper response curve",
           2.4, 20000.0, 1.5, 5.0, 0.5, 0.005, 0.2, 0, 0.010, 0.033),
  };
  SensorModel noiseless = Make("noiseless",
                               "reference without noise, blur or compression: the tone curve and "
                               "8-bit rounding only, i.e. grey values scaled by the level",
                               2.2, 6000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0.010, 0.010);
  noiseless.shot_noise = false;
  models.push_back(noiseless);
  return models;
}

}  // namespace

void SensorModel::Check() const {
  const std::string who = "sensor model '" + name + "': ";
  auto finite = [](double v) { return std::isfinite(v); };
  CheckOption(gamma > 0.0 && finite(gamma), who + "gamma must be positive");
  CheckOption(full_well_electrons >= 1.0 && finite(full_well_electrons),
              who + "full_well_electrons must be at least 1");
  CheckOption(read_noise_electrons >= 0.0 && finite(read_noise_electrons),
              who + "read_noise_electrons must be non-negative");
  CheckOption(dark_current_e_per_s >= 0.0 && finite(dark_current_e_per_s),
              who + "dark_current_e_per_s must be non-negative");
  CheckOption(dsnu_electrons >= 0.0 && finite(dsnu_electrons),
              who + "dsnu_electrons must be non-negative");
  CheckOption(prnu >= 0.0 && prnu < 0.5, who + "prnu must be in [0, 0.5)");
  CheckOption(row_noise_electrons >= 0.0 && finite(row_noise_electrons),
              who + "row_noise_electrons must be non-negative");
  CheckOption(jpeg_quality >= 0 && jpeg_quality <= 100,
              who + "jpeg_quality must be 0 (none) or 1-100");
  CheckOption(exposure_s > 0.0 && finite(exposure_s), who + "exposure_s must be positive");
  CheckOption(max_exposure_s >= exposure_s && finite(max_exposure_s),
              who + "max_exposure_s must be at least exposure_s");
}

double SensorModel::ExposureForLevel(double level) const {
  CheckOption(level > 0.0 && level <= 1.0, "low-light level must be in (0, 1]");
  return level < 1.0 ? max_exposure_s : exposure_s;
}

double SensorModel::ExtraExposureForLevel(double level) const {
  return ExposureForLevel(level) - exposure_s;
}

const std::vector<SensorModel>& SensorModels() {
  static const std::vector<SensorModel> models = BuildModels();
  return models;
}

const SensorModel& SensorModelByName(const std::string& name) {
  for (const SensorModel& model : SensorModels()) {
    if (model.name == name) return model;
  }
  throw Error("unknown sensor model '" + name + "' (known: " + SensorModelNames() + ")");
}

std::string SensorModelNames() {
  std::string names;
  for (const SensorModel& model : SensorModels()) {
    names += (names.empty() ? "" : ", ") + model.name;
  }
  return names;
}

std::string SensorModelTable() {
  std::string table =
      "| name | full well e- | read noise e- | gamma | dark current e-/s | DSNU e- | PRNU % | "
      "row noise e- | JPEG quality | exposure ms (normal / max) | description |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const SensorModel& m : SensorModels()) {
    table += cv::format(
        "| %s | %.0f | %s | %.1f | %.0f | %.1f | %.1f | %.1f | %s | %.0f / %.0f | %s |\n",
        m.name.c_str(), m.full_well_electrons,
        m.shot_noise ? cv::format("%.1f", m.read_noise_electrons).c_str() : "0 (no shot noise)",
        m.gamma, m.dark_current_e_per_s, m.dsnu_electrons, 100.0 * m.prnu, m.row_noise_electrons,
        m.jpeg_quality > 0 ? std::to_string(m.jpeg_quality).c_str() : "none", 1000.0 * m.exposure_s,
        1000.0 * m.max_exposure_s, m.description.c_str());
  }
  return table;
}

SensorModel SensorModelWithOverrides(const std::string& name, double full_well_electrons,
                                     double read_noise_electrons, double max_exposure_s) {
  SensorModel model = SensorModelByName(name);
  if (full_well_electrons > 0.0) model.full_well_electrons = full_well_electrons;
  if (read_noise_electrons >= 0.0) model.read_noise_electrons = read_noise_electrons;
  if (max_exposure_s > 0.0) model.max_exposure_s = max_exposure_s;
  if (full_well_electrons > 0.0 || read_noise_electrons >= 0.0 || max_exposure_s > 0.0) {
    model.name += "+overrides";
  }
  model.Check();
  return model;
}

}  // namespace noctua::sim
