#include "noctua/edges/edge_detector.h"

#include <utility>

#include "noctua/image/enhancement.h"
#include "noctua/util/error.h"

namespace noctua::edges {

EdgeMethod ParseEdgeMethod(const std::string& name) {
  for (EdgeMethod method : AllEdgeMethods()) {
    if (ToString(method) == name) return method;
  }
  throw Error("unknown edge method '" + name +
              "' (expected pc, pc-fast, canny, sobel, prewitt or roberts)");
}

std::string ToString(EdgeMethod method) {
  switch (method) {
    case EdgeMethod::kPhaseCongruency:
      return "pc";
    case EdgeMethod::kPhaseCongruencyFast:
      return "pc-fast";
    case EdgeMethod::kCanny:
      return "canny";
    case EdgeMethod::kSobel:
      return "sobel";
    case EdgeMethod::kPrewitt:
      return "prewitt";
    case EdgeMethod::kRoberts:
      return "roberts";
  }
  throw Error("invalid edge method value");
}

std::vector<EdgeMethod> AllEdgeMethods() {
  return {EdgeMethod::kPhaseCongruency, EdgeMethod::kPhaseCongruencyFast,
          EdgeMethod::kCanny,           EdgeMethod::kSobel,
          EdgeMethod::kPrewitt,         EdgeMethod::kRoberts};
}

void EdgeDetectorOptions::Check() const {
  reference.Check();
  fast.Check();
  reference_thresholds.Check();
  fast_thresholds.Check();
  classic.Check();
}

EdgeDetector::EdgeDetector(const EdgeDetectorOptions& options) : options_(options) {
  options_.Check();
  if (options_.method == EdgeMethod::kPhaseCongruencyFast) {
    fast_ = std::make_shared<FastPhaseCongruency>(options_.fast);
  }
}

cv::Mat EdgeDetector::Detect(const cv::Mat& image) const {
  const cv::Mat gray = image::ToGray8U(image);
  switch (options_.method) {
    case EdgeMethod::kPhaseCongruency:
      return EdgeMapFromPhaseCongruency(ComputePhaseCongruency(gray, options_.reference),
                                        options_.reference_thresholds);
    case EdgeMethod::kPhaseCongruencyFast:
      return FastEdges(gray);
    case EdgeMethod::kCanny:
      return CannyEdges(gray, options_.classic);
    case EdgeMethod::kSobel:
      return SobelEdges(gray, options_.classic);
    case EdgeMethod::kPrewitt:
      return PrewittEdges(gray, options_.classic);
    case EdgeMethod::kRoberts:
      return RobertsEdges(gray, options_.classic);
  }
  throw Error("invalid edge method value");
}

cv::Mat EdgeDetector::FastEdges(const cv::Mat& gray) const {
  if (options_.fast_full_size_nms || options_.fast.downscale == 1) {
    return EdgeMapFromPhaseCongruency(fast_->Compute(gray), options_.fast_thresholds);
  }
  const PhaseCongruency pc = fast_->ComputeAtWorkingSize(gray);
  return EnlargeEdgeMap(EdgeMapFromPhaseCongruency(pc, options_.fast_thresholds), pc, gray.size(),
                        options_.fast.downscale);
}

std::unique_ptr<EdgeDetector> CreateEdgeDetector(const EdgeDetectorOptions& options) {
  return std::make_unique<EdgeDetector>(options);
}

std::function<cv::Mat(const cv::Mat&)> MakeEdgeMapSource(
    std::shared_ptr<const EdgeDetector> detector) {
  if (!detector) throw Error("edge map source: no detector");
  return [detector = std::move(detector)](const cv::Mat& gray) { return detector->Detect(gray); };
}

}  // namespace noctua::edges
