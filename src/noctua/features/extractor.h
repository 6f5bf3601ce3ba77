#pragma once

#include <functional>
#include <map>
#include <memory>
#include <opencv2/features2d.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noctua/features/extractor_options.h"
#include "noctua/image/enhancement.h"

namespace noctua::features {

class RbriefDescriber;

// Produces a CV_8U map the size of the frame, non-zero on edge pixels, from the enhanced grey
// frame (phase congruency for the paper's method).
using EdgeMapSource = std::function<cv::Mat(const cv::Mat& enhanced_gray)>;

// Produces a CV_8U map the size of the frame, non-zero where objects may move, from the frame
// as given to the extractor (colour when the caller has colour).
using DynamicMaskSource = std::function<cv::Mat(const cv::Mat& image)>;

// What happened to one frame: how many points each stage left, which stages ran, and how long
// each took (milliseconds).
// What noise-adaptive extraction (NoiseAdaptiveOptions) chose for the frame.
struct ConditioningStats {
  double gain = 1.0;
  double noise_sigma = 0.0;  // grey levels, after the gain, at FAST's ring radius
  double blur_sigma = 0.0;   // pixels (0: none)
  int initial_fast_threshold = 0;
  int min_fast_threshold = 0;
};

struct ExtractionStats {
  int detected = 0;       // oFAST candidates over all levels, before any filter
  int after_mask = 0;     // after the caller's Feature2D mask (zero pixels exclude)
  int after_dynamic = 0;  // after filter (a)
  int after_edge = 0;     // after filter (b)
  int after_nms = 0;      // after filter (c)
  int final_count = 0;    // after distribution over the image to num_features
  // Of final_count, points the edge filter had dropped, put back on starved levels
  // (EdgeFilterOptions::fill_to_quota).
  int edge_fill = 0;
  std::vector<std::string> stages_ran;
  std::vector<std::string> stages_skipped;  // "edge-filter (no edge map source)", ...
  std::map<std::string, double> stage_ms;
  double total_ms = 0.0;
  std::optional<ConditioningStats> conditioning;  // with noise-adaptive extraction only
};

// One frame's output.
struct Extraction {
  std::vector<cv::KeyPoint> keypoints;  // ORB-SLAM semantics: level-0 pixels, octave = level
  cv::Mat descriptors;                  // N x 32 CV_8U rBRIEF (empty without descriptors)
  ExtractionStats stats;
};

// The paper's extractor (and, with stages off, ORB / HE-ORB / CLAHE-ORB), as a cv::Feature2D so it
// drops into any OpenCV pipeline. detectAndCompute honours OpenCV's mask convention (points where
// the mask is zero are removed); the dynamic mask is a separate input, with the opposite sense.
class Extractor : public cv::Feature2D {
 public:
  static cv::Ptr<Extractor> Create(const ExtractorOptions& options);

  explicit Extractor(const ExtractorOptions& options);

  // Sources for the edge map and the dynamic mask. Without a source (and without an explicit
  // map passed to Extract) the corresponding filter is skipped and reported in stats.
  void SetEdgeMapSource(EdgeMapSource source) { edge_source_ = std::move(source); }
  void SetDynamicMaskSource(DynamicMaskSource source) { dynamic_source_ = std::move(source); }

  // The full interface: image (8-bit grey, BGR or BGRA), optional dynamic mask (non-zero =
  // dynamic) and optional edge map, both of the image's size; they override the sources.
  // Throws noctua::Error for bad input.
  Extraction Extract(const cv::Mat& image, const cv::Mat& dynamic_mask = cv::Mat(),
                     const cv::Mat& edge_map = cv::Mat()) const;

  // cv::Feature2D. With useProvidedKeypoints, only descriptors are computed for the given points
  // (those where a given mask is zero are removed first, like any other detection).
  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints = false) override;
  int descriptorSize() const override { return 32; }
  int descriptorType() const override { return CV_8U; }
  int defaultNorm() const override { return cv::NORM_HAMMING; }
  cv::String getDefaultName() const override { return "noctua.Extractor"; }

  const ExtractorOptions& options() const { return options_; }
  // Statistics of the last detectAndCompute call.
  const ExtractionStats& last_stats() const { return last_stats_; }

 private:
  Extraction ExtractWithMask(const cv::Mat& image, const cv::Mat& feature2d_mask,
                             const cv::Mat& dynamic_mask, const cv::Mat& edge_map) const;

  ExtractorOptions options_;
  image::Enhancer enhancer_;
  std::shared_ptr<const RbriefDescriber> descriptor_engine_;  // null without descriptors
  EdgeMapSource edge_source_;
  DynamicMaskSource dynamic_source_;
  ExtractionStats last_stats_;
};

}  // namespace noctua::features
