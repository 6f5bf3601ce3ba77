// Not a timing benchmark: person recall of the detector in the dark, with and without the dark-
// input enhancement (dynamic/dark_input.h), on real frames darkened by every sensor model.
// Reference boxes are the detector's own person boxes at normal light with score >= 0.5 (the
// frames have no labels); a dark frame finds a reference person when one of its person boxes
// has IoU >= 0.5 with it. Frames: the 16 fr3 walking_rpy frames and the 120 bonn_crowd frames,
// darkened to LEVEL (default 0.15) as single frames (no motion blur: no depth for fr3), each with
// SEEDS noise draws (default 1; draw s of frame k has seed k + 1 + 1000 s, so draw 0 is the
// earlier single-seed table). Prints a Markdown table of recall, mean (min-max) over the draws.
// Usage: dark_detection [LEVEL] [SEEDS]
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/detector.h"
#include "noctua/sim/low_light.h"
#include "noctua/testing/shared_data.h"

namespace {

namespace fs = std::filesystem;
using noctua::dynamic::DarkEnhancement;
using noctua::dynamic::Detection;

constexpr float kReferenceScore = 0.5f;
constexpr float kMatchIoU = 0.5f;

std::vector<cv::Mat> LoadFrames(const fs::path& dir) {
  std::vector<fs::path> paths;
  for (const auto& entry : fs::directory_iterator(dir)) paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  std::vector<cv::Mat> frames;
  for (const auto& path : paths) {
    frames.push_back(noctua::testing::ReadImageOrThrow(path, cv::IMREAD_COLOR));
  }
  return frames;
}

std::vector<cv::Rect2f> People(const std::vector<Detection>& detections, float min_score) {
  const int person = noctua::dynamic::CocoClassId("person");
  std::vector<cv::Rect2f> boxes;
  for (const Detection& d : detections) {
    if (d.class_id == person && d.score >= min_score) boxes.push_back(d.box);
  }
  return boxes;
}

int Found(const std::vector<cv::Rect2f>& reference, const std::vector<cv::Rect2f>& found) {
  std::vector<bool> used(found.size(), false);
  int hits = 0;
  for (const cv::Rect2f& ref : reference) {
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (!used[i] && noctua::dynamic::IoU(ref, found[i]) >= kMatchIoU) {
        used[i] = true;
        ++hits;
        break;
      }
    }
  }
  return hits;
}

struct Mode {
  std::string name;
  bool enabled;
  DarkEnhancement method;
  double sigma;
};

}  // namespace

int main(int argc, char** argv) {
  const double level = argc > 1 ? std::stod(argv[1]) : 0.15;
  const int seeds = argc > 2 ? std::max(1, std::stoi(argv[2])) : 1;
  const fs::path model = noctua::testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx";
  const std::vector<Mode> modes = {
      {"none", false, DarkEnhancement::kGain, 0.0},
      {"gain", true, DarkEnhancement::kGain, 0.0},
      {"gamma", true, DarkEnhancement::kGamma, 0.0},
      {"smooth-gain 1.5", true, DarkEnhancement::kSmoothGain, 1.5},
      {"smooth-gain 3 (default)", true, DarkEnhancement::kSmoothGain, 3.0}};
  std::vector<std::unique_ptr<noctua::dynamic::Detector>> detectors;
  for (const Mode& mode : modes) {
    noctua::dynamic::DetectorOptions options;
    options.dark_input.enabled = mode.enabled;
    options.dark_input.method = mode.method;
    if (mode.sigma > 0.0) options.dark_input.smooth_sigma_px = mode.sigma;
    detectors.push_back(noctua::dynamic::LoadDetector(model, options));
  }
  std::cout << "| frames | sensor model | reference people";
  for (const Mode& mode : modes) std::cout << " | recall, " << mode.name;
  std::cout << " |\n|---|---|---:";
  for (std::size_t m = 0; m < modes.size(); ++m) std::cout << "|---:";
  std::cout << "|\n";
  for (const std::string set : {"tum_fr3_walking_rpy_rgb16", "bonn_crowd_120"}) {
    const std::vector<cv::Mat> frames = LoadFrames(noctua::testing::DataDir() / set / "rgb");
    std::vector<std::vector<cv::Rect2f>> reference;
    int total = 0;
    for (const cv::Mat& frame : frames) {
      reference.push_back(People(detectors[0]->Detect(frame), kReferenceScore));
      total += static_cast<int>(reference.back().size());
    }
    for (const noctua::sim::SensorModel& sensor : noctua::sim::SensorModels()) {
      if (!sensor.shot_noise) continue;
      // recall[m][s]: mode m, noise draw s.
      std::vector<std::vector<double>> recall(modes.size());
      for (int s = 0; s < seeds; ++s) {
        std::vector<int> hits(modes.size(), 0);
        for (std::size_t k = 0; k < frames.size(); ++k) {
          const cv::Mat dark = noctua::sim::DarkenToLevel(
              frames[k], level, sensor, k + 1 + 1000 * static_cast<std::size_t>(s));
          for (std::size_t m = 0; m < modes.size(); ++m) {
            hits[m] += Found(reference[k], People(detectors[m]->Detect(dark), 0.0f));
          }
        }
        for (std::size_t m = 0; m < modes.size(); ++m) {
          recall[m].push_back(hits[m] / std::max(1.0, 1.0 * total));
        }
      }
      std::cout << "| " << set << " (" << frames.size() << ") | " << sensor.name << " | " << total;
      for (const std::vector<double>& r : recall) {
        const double mean =
            std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
        if (seeds == 1) {
          std::cout << cv::format(" | %.3f", mean);
        } else {
          std::cout << cv::format(" | %.3f (%.3f-%.3f)", mean,
                                  *std::min_element(r.begin(), r.end()),
                                  *std::max_element(r.begin(), r.end()));
        }
      }
      std::cout << " |" << std::endl;
    }
  }
  return 0;
}
