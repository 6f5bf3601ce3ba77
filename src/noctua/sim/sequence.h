#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "noctua/io/camera_config.h"
#include "noctua/sim/low_light.h"
#include "noctua/sim/moving_person.h"

namespace noctua::sim {

struct SimulationOptions {
  double level = 1.0;   // mean grey left, relative to the original (1: no darkening)
  bool person = false;  // composite the walking person
  MovingPersonOptions person_options;
  // A real person's appearance for the walk (see PersonCutout); none: the drawn silhouette.
  std::optional<PersonCutout> person_cutout;
  SensorModel sensor = SensorModelByName(kDefaultSensorModel);
  // Blur each darkened frame along the ground-truth camera motion over the extra exposure the
  // model takes in the dark (motion_blur.h); frames without a ground-truth pose stay sharp.
  bool motion_blur = true;
  std::uint64_t seed = 1;  // noise seed (frame k uses seed + k)
  int max_frames = 0;      // 0: every frame of the input

  void Check() const;
};

struct SimulationReport {
  int frames = 0;
  double brightness = 1.0;           // light factor found for `level` on the first frame
  double measured_mean_ratio = 1.0;  // mean grey of all output frames / of the input frames
  double person_pixels = 0.0;        // mean share of the frame the person covers
  double exposure_s = 0.0;           // exposure of the output frames (SensorModel)
  double blur_s = 0.0;               // extra exposure blurred along the camera motion
  int blurred_frames = 0;            // frames that had a ground-truth pose to blur along
};

using SimulationProgress = std::function<void(int done, int total)>;

// Writes a TUM-layout copy of an RGB-D sequence (rgb/, depth/, rgb.txt, depth.txt,
// associations.txt, the original groundtruth.txt) darkened to `level` and, with `person`, with the
// person composited into colour and depth and its ground-truth mask in mask/ (same file names as
// rgb/). Depth is never darkened: active depth sensors work in the dark. `output` must exist
// and be empty of a previous sequence. Throws noctua::Error naming the file on failure.
SimulationReport SimulateSequence(const std::filesystem::path& input,
                                  const io::CameraConfig& camera, const SimulationOptions& options,
                                  const std::filesystem::path& output,
                                  const SimulationProgress& progress = {});

// The record of a simulation (`noctua simulate` writes it as simulation.json): its source, level,
// the sensor model's parameters, exposure and blur, seed, the person; `person_cutout` is the
// cut-out image's path ("" for none).
std::string SimulationRecordJson(const std::filesystem::path& source,
                                 const SimulationOptions& options, const SimulationReport& report,
                                 const std::string& person_cutout);

// One line for a person: frames, where, mean grey ratio, light factor, sensor, blur, person.
std::string SimulationSummary(const SimulationOptions& options, const SimulationReport& report,
                              const std::filesystem::path& output);

}  // namespace noctua::sim
