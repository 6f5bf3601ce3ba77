#include "noctua/sim/sequence.h"

#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "noctua/io/dataset.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/sim/motion_blur.h"
#include "noctua/util/error.h"

namespace noctua::sim {

namespace fs = std::filesystem;

void SimulationOptions::Check() const {
  CheckOption(level > 0.0 && level <= 1.0, "simulation level must be in (0, 1]");
  CheckOption(max_frames >= 0, "simulation max_frames must be 0 (all) or positive");
  sensor.Check();
  person_options.Check();
  if (person_cutout) {
    CheckOption(person, "a person cut-out is given but the person is off");
    person_cutout->Check();
  }
}

namespace {

std::string Stamp(double t) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(6) << t;
  return out.str();
}

}  // namespace

SimulationReport SimulateSequence(const fs::path& input, const io::CameraConfig& camera,
                                  const SimulationOptions& options, const fs::path& output,
                                  const SimulationProgress& progress) {
  options.Check();
  camera.Check();
  const io::Sequence sequence =
      io::Sequence::Open(input, {.ground_truth_convention = camera.ground_truth});
  const fs::path ground_truth = input / "groundtruth.txt";
  if (!fs::is_regular_file(ground_truth)) {
    ThrowFileError(ground_truth, "missing: a simulated sequence keeps the original ground truth");
  }
  if (!fs::is_directory(output)) ThrowFileError(output, "output folder does not exist");
  const int total = options.max_frames > 0
                        ? std::min<int>(options.max_frames, static_cast<int>(sequence.size()))
                        : static_cast<int>(sequence.size());
  SimulationReport report;
  report.frames = total;
  std::unique_ptr<LowLightSimulator> darkener;
  report.exposure_s = options.sensor.ExposureForLevel(options.level);
  if (options.level < 1.0) {
    report.brightness = BrightnessForMeanRatio(io::ReadImage8U(sequence.frame(0).rgb_path),
                                               options.level, options.sensor);
    darkener = std::make_unique<LowLightSimulator>(options.sensor, report.brightness);
    if (options.motion_blur) report.blur_s = options.sensor.ExtraExposureForLevel(options.level);
  }
  std::unique_ptr<MovingPerson> person;
  if (options.person) {
    person = options.person_cutout
                 ? std::make_unique<MovingPerson>(options.person_options, camera.intrinsics.fy,
                                                  camera.depth_factor, *options.person_cutout)
                 : std::make_unique<MovingPerson>(options.person_options, camera.intrinsics.fy,
                                                  camera.depth_factor);
  }
  for (const char* folder : {"rgb", "depth", "mask"}) {
    if (std::string(folder) == "mask" && !person) continue;
    fs::create_directories(output / folder);
  }
  std::ostringstream rgb_list, depth_list, associations;
  rgb_list << "# color images (noctua simulate)\n# timestamp filename\n";
  depth_list << "# depth maps (noctua simulate, 16-bit, unchanged scale)\n# timestamp filename\n";
  double input_sum = 0.0, output_sum = 0.0, person_sum = 0.0;
  for (int k = 0; k < total; ++k) {
    const io::Frame& frame = sequence.frame(static_cast<std::size_t>(k));
    cv::Mat image = io::ReadImage8U(frame.rgb_path);
    cv::Mat depth = io::ReadDepth16U(frame.depth_path);
    if (depth.size() != image.size()) {
      ThrowFileError(frame.depth_path, "depth and colour images differ in size");
    }
    input_sum += cv::mean(image.reshape(1))[0];
    cv::Mat mask;
    if (person) {
      const double progress_k = total > 1 ? static_cast<double>(k) / (total - 1) : 0.5;
      PersonFrame composed = person->Composite(image, depth, progress_k);
      image = composed.image;
      depth = composed.depth;
      mask = composed.mask;
      person_sum += cv::countNonZero(mask) / static_cast<double>(mask.total());
    }
    if (report.blur_s > 0.0) {
      const std::vector<geometry::Pose> poses =
          ExposurePoses(sequence.ground_truth(), frame.timestamp, report.blur_s);
      if (!poses.empty()) {
        image = BlurAlongCameraMotion(image, io::DepthToMetres(depth, camera.depth_factor),
                                      camera.intrinsics, poses);
        ++report.blurred_frames;
      }
    }
    if (darkener) {
      cv::RNG rng(options.seed + static_cast<std::uint64_t>(k));
      image = darkener->Apply(image, rng);
    }
    output_sum += cv::mean(image.reshape(1))[0];
    const std::string rgb_name = frame.rgb_path.filename().string();
    const std::string depth_name = frame.depth_path.filename().string();
    io::WriteImage(output / "rgb" / rgb_name, image);
    io::WriteImage(output / "depth" / depth_name, depth);
    if (person) io::WriteImage(output / "mask" / rgb_name, mask);
    rgb_list << Stamp(frame.timestamp) << " rgb/" << rgb_name << "\n";
    depth_list << Stamp(frame.depth_timestamp) << " depth/" << depth_name << "\n";
    associations << Stamp(frame.timestamp) << " rgb/" << rgb_name << " "
                 << Stamp(frame.depth_timestamp) << " depth/" << depth_name << "\n";
    if (progress) progress(k + 1, total);
  }
  io::WriteTextFileAtomically(output / "rgb.txt", rgb_list.str());
  io::WriteTextFileAtomically(output / "depth.txt", depth_list.str());
  io::WriteTextFileAtomically(output / "associations.txt", associations.str());
  fs::copy_file(ground_truth, output / "groundtruth.txt", fs::copy_options::overwrite_existing);
  report.measured_mean_ratio = input_sum > 0.0 ? output_sum / input_sum : 0.0;
  report.person_pixels = total > 0 ? person_sum / total : 0.0;
  return report;
}

namespace {

nlohmann::json SensorJson(const SensorModel& s) {
  return {{"name", s.name},
          {"gamma", s.gamma},
          {"full_well_electrons", s.full_well_electrons},
          {"shot_noise", s.shot_noise},
          {"read_noise_electrons", s.read_noise_electrons},
          {"dark_current_e_per_s", s.dark_current_e_per_s},
          {"dsnu_electrons", s.dsnu_electrons},
          {"prnu", s.prnu},
          {"row_noise_electrons", s.row_noise_electrons},
          {"jpeg_quality", s.jpeg_quality},
          {"exposure_s", s.exposure_s},
          {"max_exposure_s", s.max_exposure_s}};
}

}  // namespace

std::string SimulationRecordJson(const std::filesystem::path& source,
                                 const SimulationOptions& options, const SimulationReport& report,
                                 const std::string& person_cutout) {
  const nlohmann::json json = {
      {"source", std::filesystem::absolute(source).lexically_normal().string()},
      {"frames", report.frames},
      {"level", options.level},
      {"brightness_factor", report.brightness},
      {"measured_mean_ratio", report.measured_mean_ratio},
      {"sensor", SensorJson(options.sensor)},
      {"exposure_s", report.exposure_s},
      {"motion_blur_s", report.blur_s},
      {"blurred_frames", report.blurred_frames},
      {"seed", options.seed},
      {"person", options.person},
      {"person_distance_m", options.person_options.distance_m},
      {"person_cutout", person_cutout},
      {"person_mean_coverage", report.person_pixels}};
  return json.dump(2) + "\n";
}

std::string SimulationSummary(const SimulationOptions& options, const SimulationReport& report,
                              const std::filesystem::path& output) {
  std::ostringstream line;
  line << "simulated " << report.frames << " frames into " << output.string()
       << " (mean grey ratio " << report.measured_mean_ratio << ", light factor "
       << report.brightness << ", sensor " << options.sensor.name << ", " << report.blurred_frames
       << " frames blurred over " << 1000.0 * report.blur_s << " ms"
       << (options.person ? ", with the walking person" : "") << ")\n";
  return line.str();
}

}  // namespace noctua::sim
