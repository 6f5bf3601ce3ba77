#pragma once

#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noctua/io/camera_config.h"
#include "noctua/io/dataset.h"
#include "noctua/io/frame_source.h"
#include "noctua/pipeline/method.h"

namespace noctua::eval {

// The feature-count and matching protocol (SPEC §3).
struct FeatureEvalOptions {
  int gap = 20;                           // frame i is matched against frame i + gap
  int pair_step = 1;                      // evaluate the pairs starting at every pair_step frames
  int max_frames = 0;                     // 0: the whole sequence
  double ratio = 0.8;                     // Lowe's ratio test
  std::vector<double> taus = {3, 5, 10};  // correctness thresholds reported, pixels, ascending
  int showcase_pair = -1;                 // pair drawn in the match images (-1: the middle one)

  void Check() const;
};

struct FrameCount {
  int frame = 0;
  double timestamp = 0.0;
  int count = 0;
  double extract_ms = 0.0;
};

struct PairScore {
  int frame_i = 0;
  int frame_j = 0;
  int matches = 0;
  int no_depth = 0;           // matches whose point in frame i has no depth (not judged)
  int on_dynamic = 0;         // matches touching a moving object (judged wrong)
  std::vector<int> correct;   // per tau
  int comparable = 0;         // frame i's points that frame j sees (Repeatability)
  std::vector<int> repeated;  // per tau: of those, the ones frame j detected again
};

struct MethodScore {
  std::string method;
  std::vector<FrameCount> counts;
  std::vector<PairScore> pairs;
  std::vector<double> errors_px;  // reprojection errors of all judged, static matches
  cv::Mat showcase;  // the showcase pair drawn: correct green, wrong red, no depth grey
};

struct FeatureEvalResult {
  std::string dataset;
  std::vector<double> taus;
  double default_tau = 5.0;
  std::vector<MethodScore> methods;
};

// A sequence as the evaluation reads it: frames with ground truth and depth, and optionally a
// ground-truth dynamic mask per frame (simulated sequences: mask/<rgb file name>).
class EvalSequence {
 public:
  // Opens a TUM or OpenLORIS layout sequence. Throws noctua::Error naming the folder when it has
  // no ground truth.
  EvalSequence(const std::filesystem::path& dir, const io::CameraConfig& camera);
  // Reads the frames of a source (e.g. a ROS bag, io::RosBagSource) that have a ground-truth
  // pose (the source's ground_truth() interpolated at the colour image's time, as a folder's
  // are), at most `max_frames` of them (0: all), into memory. `name` is the report's dataset
  // name. A source has no dynamic masks. Throws noctua::Error naming the source when it has no
  // ground truth, or no frame within it.
  EvalSequence(io::FrameSource& source, const io::CameraConfig& camera, std::string name,
               std::size_t max_frames = 0);

  std::size_t size() const { return frames_.size(); }
  const io::Frame& frame(std::size_t i) const { return frames_[i]; }
  const io::CameraConfig& camera() const { return camera_; }
  // The folder's name, or the name given with the source.
  const std::string& name() const { return name_; }
  bool has_dynamic_masks() const { return has_masks_; }
  io::FrameImages Load(std::size_t i) const;
  // Empty when the sequence has no masks.
  cv::Mat LoadDynamicMask(std::size_t i) const;

 private:
  std::optional<io::Sequence> sequence_;  // a folder's; none for a source's frames
  io::CameraConfig camera_;
  std::string name_;
  std::vector<io::Frame> frames_;        // those with a ground-truth pose
  std::vector<io::FrameImages> images_;  // a source's frames, read once
  bool has_masks_ = false;
};

// Opens the recording the options name (a folder or a bag, no camera and no real-time replay)
// for the evaluation: a folder as EvalSequence(dir, camera), a bag's frames with its ground
// truth file; the first `max_frames` frames with ground truth (0: all). Throws noctua::Error
// naming the file and problem.
EvalSequence OpenEvalSequence(io::FrameSourceOptions source, const io::CameraConfig& camera,
                              std::size_t max_frames = 0);

using Progress = std::function<void(const std::string& message)>;

// Runs every method on every frame (counts), matches the pairs (i, i + gap), judges them, and
// picks the default tau from all methods' error distribution. Throws noctua::Error for bad
// options or data.
FeatureEvalResult EvaluateFeatures(const EvalSequence& sequence,
                                   std::vector<std::unique_ptr<pipeline::FeatureMethod>>& methods,
                                   const FeatureEvalOptions& options,
                                   const Progress& progress = {});

// Summary figures of one method.
struct MethodSummary {
  double mean_count = 0.0;
  double mean_matches = 0.0;   // per pair
  double mean_no_depth = 0.0;  // per pair
  double mean_on_dynamic = 0.0;
  std::vector<double> mean_correct;  // per tau, per pair
  std::vector<double> rate;          // per tau: correct / judged (matches with depth)
  // Per tau: repeated / comparable over all pairs, whatever the descriptors say (Repeatability).
  std::vector<double> repeatability;
};
MethodSummary Summarize(const MethodScore& score, std::size_t num_taus);

// The mean count of each block of 10 frames (the paper's Figures 8 and 11).
std::vector<double> MeanPerTenFrames(const std::vector<FrameCount>& counts);

// Markdown table: methods x count, matches, correct matches, rate and repeatability at the
// default tau, and the rate at every tau.
std::string SummaryMarkdown(const FeatureEvalResult& result);

// Writes counts.csv, counts_mean10.csv, pairs.csv, errors.csv, summary.md, summary.json, the
// gnuplot plots counts.png, counts_mean10.png, correct_rate.png, errors.png, and
// matches_<method>.png into `dir` (which must exist). Throws noctua::Error naming the file.
void WriteFeatureEvalReport(const FeatureEvalResult& result, const std::filesystem::path& dir);

}  // namespace noctua::eval
