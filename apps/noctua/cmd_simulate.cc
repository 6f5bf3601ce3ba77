// noctua simulate: low-light and moving-person versions of a real RGB-D sequence.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "noctua/dynamic/dynamic_mask.h"
#include "noctua/image/enhancement.h"
#include "noctua/io/camera_config.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/sim/sequence.h"
#include "noctua/util/error.h"

namespace noctua::app {
namespace {

namespace fs = std::filesystem;

struct SimulateFlags {
  std::string dataset;
  std::string camera;
  std::string out;
  double level_percent = 100.0;
  bool person = false;
  double person_distance_m = sim::MovingPersonOptions{}.distance_m;
  std::string person_cutout;  // image with a real person to composite
  std::string person_mask;    // its mask, or
  std::string seg_model;      // a segmentation model that finds it
  std::uint64_t seed = 1;
  int max_frames = 0;
  std::string sensor = sim::kDefaultSensorModel;
  double full_well = 0.0;        // 0: the model's
  double read_noise = -1.0;      // negative: the model's
  double max_exposure_ms = 0.0;  // 0: the model's
  bool no_blur = false;
  bool list_sensors = false;
  bool force = false;
};

// The real person of --person-cutout: the mask given, or the largest person the segmentation
// model finds.
sim::PersonCutout LoadCutout(const SimulateFlags& flags) {
  cv::Mat image = io::ReadImage8U(flags.person_cutout);
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  cv::Mat mask;
  if (!flags.person_mask.empty()) {
    mask = image::ToGray8U(io::ReadImage8U(flags.person_mask));
    if (mask.size() != image.size()) {
      ThrowFileError(flags.person_mask, "person mask is not of the cut-out image's size");
    }
    if (cv::countNonZero(mask) == 0) ThrowFileError(flags.person_mask, "person mask is empty");
  } else {
    mask = dynamic::FindLargestPersonMask(image, flags.person_cutout, flags.seg_model);
  }
  return sim::PersonCutout::FromMask(image, mask);
}

void RunSimulate(const SimulateFlags& flags) {
  if (flags.list_sensors) {
    std::cout << sim::SensorModelTable();
    return;
  }
  for (const auto& [value, name] :
       {std::pair{&flags.dataset, "--dataset"}, std::pair{&flags.camera, "--camera"},
        std::pair{&flags.out, "--out"}}) {
    if (value->empty()) throw Error(std::string("simulate needs ") + name);
  }
  if (!(flags.level_percent > 0.0 && flags.level_percent <= 100.0)) {
    throw Error("--level must be a percentage in (0, 100]");
  }
  const io::CameraConfig camera = io::ReadCameraConfig(flags.camera);
  sim::SimulationOptions options;
  options.level = flags.level_percent / 100.0;
  options.person = flags.person || !flags.person_cutout.empty();
  if (!flags.person_cutout.empty()) {
    if (flags.person_mask.empty() == flags.seg_model.empty()) {
      throw Error("--person-cutout needs exactly one of --person-mask and --seg-model");
    }
    options.person_cutout = LoadCutout(flags);
  } else if (!flags.person_mask.empty() || !flags.seg_model.empty()) {
    throw Error("--person-mask and --seg-model only apply with --person-cutout");
  }
  options.person_options.distance_m = flags.person_distance_m;
  options.sensor = sim::SensorModelWithOverrides(flags.sensor, flags.full_well, flags.read_noise,
                                                 flags.max_exposure_ms / 1000.0);
  options.motion_blur = !flags.no_blur;
  options.seed = flags.seed;
  options.max_frames = flags.max_frames;
  options.Check();
  const fs::path out(flags.out);
  io::PrepareOutputDir(out, flags.force);
  const sim::SimulationReport report =
      sim::SimulateSequence(flags.dataset, camera, options, out, [](int done, int total) {
        if (done % 25 == 0 || done == total) spdlog::info("simulated {}/{} frames", done, total);
      });
  fs::copy_file(flags.camera, out / "camera.yaml", fs::copy_options::overwrite_existing);
  io::WriteTextFileAtomically(
      out / "simulation.json",
      sim::SimulationRecordJson(flags.dataset, options, report, flags.person_cutout));
  std::cout << sim::SimulationSummary(options, report, out);
}

}  // namespace

void AddSimulateCommand(CLI::App& app) {
  auto flags = std::make_shared<SimulateFlags>();
  CLI::App* command = app.add_subcommand(
      "simulate", "Low-light and moving-person versions of a TUM/OpenLORIS RGB-D sequence");
  command->add_option("-d,--dataset", flags->dataset, "Input sequence folder (required)")
      ->check(CLI::ExistingDirectory);
  command
      ->add_option("--camera", flags->camera, "Camera preset, e.g. config/tum_fr1.yaml (required)")
      ->check(CLI::ExistingFile);
  command->add_option("-o,--out", flags->out, "Output folder, TUM layout (required)");
  command->add_option("--sensor", flags->sensor, "Sensor model: " + sim::SensorModelNames())
      ->capture_default_str();
  command->add_flag("--list-sensors", flags->list_sensors,
                    "Print the sensor models and their parameters, then exit");
  command->add_flag("--no-blur", flags->no_blur,
                    "No motion blur along the ground-truth motion over the longer exposure");
  command
      ->add_option("--level", flags->level_percent,
                   "Mean grey left, in percent of the original (100: no darkening)")
      ->capture_default_str();
  command->add_flag("--person", flags->person, "Composite a person walking across the frames");
  command
      ->add_option("--person-distance", flags->person_distance_m,
                   "Distance of the person from the camera, metres")
      ->capture_default_str();
  command
      ->add_option("--person-cutout", flags->person_cutout,
                   "Composite this real person (an image with one in it) in place of the drawn one")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--person-mask", flags->person_mask,
                   "Mask PNG of the person in the --person-cutout image (non-zero on the person)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--seg-model", flags->seg_model,
                   "Or: a YOLOv8-seg ONNX model that finds the largest person in that image")
      ->check(CLI::ExistingFile);
  command->add_option("--full-well", flags->full_well, "Override the model's full well, electrons");
  command->add_option("--read-noise", flags->read_noise,
                      "Override the model's read noise, electrons rms");
  command->add_option("--max-exposure-ms", flags->max_exposure_ms,
                      "Override the model's longest exposure, ms (a dark frame's: a shorter one "
                      "blurs less and leaves the frame darker)");
  command->add_option("--seed", flags->seed, "Noise seed")->capture_default_str();
  command->add_option("--max-frames", flags->max_frames, "Only the first N frames (0: all)")
      ->capture_default_str();
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags] { RunSimulate(*flags); });
}

}  // namespace noctua::app
