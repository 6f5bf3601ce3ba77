#pragma once

#include <filesystem>
#include <iosfwd>
#include <opencv2/core.hpp>
#include <string>

#include "noctua/sim/sensor_model.h"

namespace noctua::demo {

// A desk-like scene: textured posters, books, a checkerboard and text on a lit wall, and a
// person-shaped region that the paper's dynamic filter must clear.
struct DemoScene {
  cv::Mat image;        // 640x480 BGR
  cv::Mat person_mask;  // CV_8U, 255 on the person
};
DemoScene MakeDemoScene(unsigned seed);

struct DemoOptions {
  unsigned seed = 7;  // of the generated scene and the darkening's noise
  // The sensor model (sim/sensor_model.h) that darkens the scene to 15 %.
  std::string sensor = sim::kDefaultSensorModel;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// What `noctua demo` shows: extraction on the scene in normal light and at 15% (overlays,
// summary.md, summary.json), then the scene as a 24-frame sequence evaluated end to end
// (evaluation.md, eval_*/), all written into `out_dir` (which must exist). The tables go to `log`
// as they are ready (the evaluation takes a while); returns them all.
std::string RunDemo(const DemoOptions& options, const std::filesystem::path& out_dir,
                    std::ostream& log);

// End to end on a short generated sequence: `scene` on a wall seen by a moving camera (exact
// depth and poses), made dark (15%) with the walking person, then the feature evaluation judged
// by that ground truth. Returns the summary tables.
std::string EvaluateDemoSequence(const cv::Mat& scene, const std::filesystem::path& out_dir);

}  // namespace noctua::demo
