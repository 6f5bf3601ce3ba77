#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace noctua::eval {

// Timing of every stage and every method on real frames, each against OpenCV's ORB timed
// interleaved on the same frames in the same run, so that the ratio holds whatever else the
// machine is doing (`noctua bench`).
struct BenchOptions {
  std::filesystem::path dataset;  // sequence folder (TUM / OpenLORIS)
  std::filesystem::path config;   // settings file: camera, SLAM and extractor
  std::string detector_model;     // adds paper+detector and the detector stages ("" = none)
  int frames = 30;                // consecutive frames from the start
  int repeat = 3;                 // repetitions over the frames
  int threads = 1;                // cv::setNumThreads; 1 also runs the extractor's stages in turn

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Samples of one row, kept per repetition so that the spread can be given as the range of the
// per-repetition medians.
class BenchSamples {
 public:
  void Add(int repetition, double ms);
  std::vector<double> All() const;
  double Median() const;
  std::pair<double, double> RepetitionMedianRange() const;
  std::size_t count() const { return All().size(); }

 private:
  std::vector<std::vector<double>> per_repetition_;
};

struct BenchRow {
  std::string group;  // "stage" or "method"
  std::string name;
  std::string what;  // where the time comes from
  BenchSamples ms;
  std::vector<double> keypoints;  // methods only
};

// Rows in the order they were first named.
class BenchTable {
 public:
  BenchRow& Get(const std::string& group, const std::string& name, const std::string& what);
  const std::vector<BenchRow>& rows() const { return rows_; }

 private:
  std::vector<BenchRow> rows_;
  std::map<std::string, std::size_t> index_;
};

struct BenchResult {
  BenchOptions options;
  std::size_t frames = 0;  // loaded (fewer than asked when the sequence is shorter)
  BenchTable table;
  BenchSamples reference_ms;            // OpenCV ORB, 1000 points, grey conversion included
  std::vector<double> matches;          // ratio-test survivors per consecutive frame pair
  std::string load_before = "unknown";  // 1-minute load average around the run
  std::string load_after = "unknown";
  double wall_s = 0.0;
};

// Runs the bench; `log` receives a line after each phase (e.g. for stderr).
BenchResult RunBench(const BenchOptions& options,
                     const std::function<void(const std::string&)>& log = {});

// bench.json, bench.md and the gnuplot data of the methods' bars.
struct BenchReport {
  nlohmann::json json;
  std::string markdown;
  std::string plot_data;
};
// Throws noctua::Error when the reference took no measurable time.
BenchReport MakeBenchReport(const BenchResult& result);

// Writes bench.json, bench.md, bench_methods.dat, bench.gp and bench.png (gnuplot) into `out`.
void WriteBenchReport(const BenchReport& report, const std::filesystem::path& out);

// Matches of `query` in `train` by 2-NN Hamming distance that pass Lowe's ratio test.
std::size_t CountRatioTestMatches(const cv::Mat& query, const cv::Mat& train, float ratio);

}  // namespace noctua::eval
