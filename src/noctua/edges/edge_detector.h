#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "noctua/edges/classic.h"
#include "noctua/edges/edge_map.h"
#include "noctua/edges/phase_congruency.h"

namespace noctua::edges {

enum class EdgeMethod {
  kPhaseCongruency,      // "pc": phasecong3, the reference
  kPhaseCongruencyFast,  // "pc-fast": the monogenic fast variant, for every frame
  kCanny,                // "canny": Gaussian + Canny
  kSobel,                // "sobel"
  kPrewitt,              // "prewitt"
  kRoberts,              // "roberts"
};

// Parses the names above; throws noctua::Error listing them on anything else.
EdgeMethod ParseEdgeMethod(const std::string& name);
std::string ToString(EdgeMethod method);
// All methods, in the order of the comparison panel.
std::vector<EdgeMethod> AllEdgeMethods();

struct EdgeDetectorOptions {
  EdgeMethod method = EdgeMethod::kPhaseCongruencyFast;
  PhaseCongruencyOptions reference;
  FastPhaseCongruencyOptions fast;
  EdgeMapOptions reference_thresholds;  // NMS + hysteresis on the reference's M
  // The fast variant's PC runs higher than phasecong3's M on the same edges (no moment over
  // orientations). 0.2 / 0.35 gave the best agreement with the reference's map on fr1 frames,
  // normal and darkened, with almost no edges in pure noise (docs/edges.md); with
  // fast_full_size_nms the pair was 0.2 / 0.3.
  EdgeMapOptions fast_thresholds{0.2, 0.35};
  // Where the fast variant's map is thinned and cut. false: at PC's working size, then drawn
  // into the full-size map at sub-pixel positions (EnlargeEdgeMap), which skips interpolating
  // PC to every full-size pixel (about 1.5 ms less per 640x480 frame). true: at full size, on
  // the interpolated PC. Both give lines one pixel wide and agree with the reference within
  // 0.02 of F (docs/edges.md).
  bool fast_full_size_nms = false;
  ClassicEdgeOptions classic;

  void Check() const;
};

// One edge detector: image in, CV_8U map of its size out (255 on edges).
class EdgeDetector {
 public:
  explicit EdgeDetector(const EdgeDetectorOptions& options);

  // Accepts 8-bit grey, BGR or BGRA (converted to grey). Throws noctua::Error for bad input.
  cv::Mat Detect(const cv::Mat& image) const;

  const EdgeDetectorOptions& options() const { return options_; }

 private:
  cv::Mat FastEdges(const cv::Mat& gray) const;

  EdgeDetectorOptions options_;
  std::shared_ptr<FastPhaseCongruency> fast_;  // filters cached across frames
};

std::unique_ptr<EdgeDetector> CreateEdgeDetector(const EdgeDetectorOptions& options);

// Wraps a detector as the extractor's edge-map source (a std::function, so that edges/ does not
// depend on features/); the detector is shared, its filter cache reused frame after frame.
std::function<cv::Mat(const cv::Mat&)> MakeEdgeMapSource(
    std::shared_ptr<const EdgeDetector> detector);

}  // namespace noctua::edges
