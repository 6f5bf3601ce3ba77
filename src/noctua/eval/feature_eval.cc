#include "noctua/eval/feature_eval.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "noctua/eval/match_judge.h"
#include "noctua/eval/trajectory_plot.h"
#include "noctua/features/ofast.h"
#include "noctua/io/image_file.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::eval {

namespace fs = std::filesystem;

void FeatureEvalOptions::Check() const {
  CheckOption(gap >= 1, "eval gap must be at least 1");
  CheckOption(pair_step >= 1, "eval pair_step must be at least 1");
  CheckOption(max_frames >= 0, "eval max_frames must be 0 (all) or positive");
  CheckOption(ratio > 0.0 && ratio <= 1.0, "eval ratio must be in (0, 1]");
  CheckOption(!taus.empty() && std::is_sorted(taus.begin(), taus.end()) && taus.front() > 0.0,
              "eval taus must be positive and ascending");
}

EvalSequence::EvalSequence(const fs::path& dir, const io::CameraConfig& camera)
    : sequence_(io::Sequence::Open(dir, {.ground_truth_convention = camera.ground_truth})),
      camera_(camera) {
  camera_.Check();
  if (!sequence_->has_ground_truth()) {
    ThrowFileError(dir,
                   "the sequence has no ground truth (groundtruth.txt): matches cannot be "
                   "judged");
  }
  for (const auto& frame : sequence_->frames()) {
    if (frame.ground_truth) frames_.push_back(frame);
  }
  if (frames_.empty()) ThrowFileError(dir, "no frame lies within the ground truth's time span");
  name_ = frames_.front().rgb_path.parent_path().parent_path().filename().string();
  has_masks_ = fs::is_directory(dir / "mask");
}

EvalSequence::EvalSequence(io::FrameSource& source, const io::CameraConfig& camera,
                           std::string name, std::size_t max_frames)
    : camera_(camera), name_(std::move(name)) {
  camera_.Check();
  const io::Trajectory& truth = source.ground_truth();
  if (truth.empty()) {
    throw Error(source.Describe() +
                ": no ground truth (a TUM groundtruth file): matches cannot "
                "be judged");
  }
  const double max_gap_s = io::SequenceOptions{}.max_ground_truth_gap_s;  // as a folder's frames
  const cv::Size size = camera_.Camera().size();
  while (max_frames == 0 || frames_.size() < max_frames) {
    std::optional<io::SourceFrame> next = source.Next();
    if (!next) break;
    std::optional<geometry::Pose> pose = truth.Interpolate(next->timestamp, max_gap_s);
    if (!pose) continue;
    if (next->images.bgr.size() != size) {
      throw Error(source.Describe() + ", frame " + std::to_string(next->index) + ": image size " +
                  std::to_string(next->images.bgr.cols) + "x" +
                  std::to_string(next->images.bgr.rows) + " differs from the camera's " +
                  std::to_string(size.width) + "x" + std::to_string(size.height));
    }
    io::Frame frame;
    frame.index = next->index;
    frame.timestamp = next->timestamp;
    frame.ground_truth = pose;
    frames_.push_back(std::move(frame));
    images_.push_back(std::move(next->images));
  }
  if (frames_.empty()) {
    throw Error(source.Describe() + ": no frame lies within the ground truth's time span");
  }
}

io::FrameImages EvalSequence::Load(std::size_t i) const {
  if (!sequence_) return images_.at(i);
  io::FrameImages images = sequence_->Load(frames_.at(i), camera_.depth_factor);
  if (images.bgr.size() != camera_.Camera().size()) {
    ThrowFileError(frames_[i].rgb_path, "image size differs from the camera's");
  }
  return images;
}

EvalSequence OpenEvalSequence(io::FrameSourceOptions source, const io::CameraConfig& camera,
                              std::size_t max_frames) {
  CheckOption(!source.live.has_value(),
              "eval reads a recording (a folder or a bag), not a camera: a camera has no ground "
              "truth to judge matches with");
  CheckOption(source.replay_rate == 0.0, "eval reads every frame: replay_rate does not apply");
  source.Check();
  if (!source.dataset.empty()) return EvalSequence(source.dataset, camera);
  if (source.ground_truth.empty()) {
    ThrowFileError(source.bag,
                   "eval needs the bag's ground truth (--groundtruth FILE, TUM format): matches "
                   "are judged with it");
  }
  source.ground_truth_convention = camera.ground_truth;
  source.max_frames = 0;  // max_frames counts the frames with ground truth, as for a folder
  const std::unique_ptr<io::FrameSource> frames = io::OpenFrameSource(source);
  return EvalSequence(*frames, camera, source.bag.filename().string(), max_frames);
}

cv::Mat EvalSequence::LoadDynamicMask(std::size_t i) const {
  if (!has_masks_) return {};
  const fs::path path = sequence_->dir() / "mask" / frames_.at(i).rgb_path.filename();
  cv::Mat mask = io::ReadImage8U(path);
  if (mask.channels() != 1 || mask.size() != camera_.Camera().size()) {
    ThrowFileError(path, "a dynamic mask must be a grey image of the frames' size");
  }
  return mask;
}

namespace {

struct Extracted {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

cv::Mat DrawPair(const cv::Mat& image_i, const std::vector<cv::KeyPoint>& keypoints_i,
                 const cv::Mat& image_j, const std::vector<cv::KeyPoint>& keypoints_j,
                 const std::vector<JudgedMatch>& judged, double tau) {
  cv::Mat canvas;
  cv::hconcat(image_i, image_j, canvas);
  if (canvas.channels() == 1) cv::cvtColor(canvas, canvas, cv::COLOR_GRAY2BGR);
  const cv::Point2f offset(static_cast<float>(image_i.cols), 0.0f);
  for (const auto& match : judged) {
    const cv::Point2f a = keypoints_i[static_cast<std::size_t>(match.match.queryIdx)].pt;
    const cv::Point2f b = keypoints_j[static_cast<std::size_t>(match.match.trainIdx)].pt + offset;
    cv::Scalar colour(160, 160, 160);
    if (match.has_depth)
      colour = IsCorrect(match, tau) ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 0, 255);
    cv::line(canvas, a, b, colour, 1, cv::LINE_AA);
    cv::circle(canvas, a, 3, colour, 1, cv::LINE_AA);
    cv::circle(canvas, b, 3, colour, 1, cv::LINE_AA);
  }
  return canvas;
}

}  // namespace

FeatureEvalResult EvaluateFeatures(const EvalSequence& sequence,
                                   std::vector<std::unique_ptr<pipeline::FeatureMethod>>& methods,
                                   const FeatureEvalOptions& options, const Progress& progress) {
  options.Check();
  if (methods.empty()) throw Error("eval needs at least one method");
  const std::size_t num_frames = options.max_frames > 0
                                     ? std::min<std::size_t>(sequence.size(), options.max_frames)
                                     : sequence.size();
  const std::size_t gap = static_cast<std::size_t>(options.gap);
  if (num_frames <= gap) {
    throw Error("eval: the sequence has " + std::to_string(num_frames) +
                " frames with ground truth, not more than the gap " + std::to_string(gap));
  }
  const geometry::PinholeCamera camera = sequence.camera().Camera();
  std::vector<std::size_t> pair_starts;
  for (std::size_t i = 0; i + gap < num_frames; i += static_cast<std::size_t>(options.pair_step)) {
    pair_starts.push_back(i);
  }
  const std::size_t showcase =
      options.showcase_pair >= 0
          ? std::min<std::size_t>(static_cast<std::size_t>(options.showcase_pair),
                                  pair_starts.size() - 1)
          : pair_starts.size() / 2;

  FeatureEvalResult result;
  result.dataset = sequence.name();
  result.taus = options.taus;
  result.methods.resize(methods.size());
  std::vector<std::vector<Extracted>> extracted(methods.size(), std::vector<Extracted>(num_frames));
  std::vector<io::FrameImages> images(num_frames);
  std::vector<cv::Mat> masks(num_frames);
  for (std::size_t f = 0; f < num_frames; ++f) {
    images[f] = sequence.Load(f);
    masks[f] = sequence.LoadDynamicMask(f);
    for (std::size_t m = 0; m < methods.size(); ++m) {
      Stopwatch watch;
      features::Extraction extraction = methods[m]->Run(images[f].bgr);
      const double ms = watch.ElapsedMs();
      result.methods[m].counts.push_back({static_cast<int>(f), sequence.frame(f).timestamp,
                                          static_cast<int>(extraction.keypoints.size()), ms});
      extracted[m][f] = {std::move(extraction.keypoints), std::move(extraction.descriptors)};
    }
    if (progress && ((f + 1) % 20 == 0 || f + 1 == num_frames)) {
      progress("extracted " + std::to_string(f + 1) + "/" + std::to_string(num_frames) + " frames");
    }
  }

  for (std::size_t p = 0; p < pair_starts.size(); ++p) {
    const std::size_t i = pair_starts[p];
    const std::size_t j = i + gap;
    PairGeometry geometry{
        camera, sequence.frame(j).ground_truth->inverse() * *sequence.frame(i).ground_truth,
        images[i].depth_m, masks[i], masks[j]};
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const Extracted& a = extracted[m][i];
      const Extracted& b = extracted[m][j];
      const auto matches =
          MatchWithRatioTest(a.descriptors, b.descriptors, methods[m]->norm_type(), options.ratio);
      const auto judged = JudgeMatches(a.keypoints, b.keypoints, matches, geometry);
      PairScore score;
      score.frame_i = static_cast<int>(i);
      score.frame_j = static_cast<int>(j);
      score.matches = static_cast<int>(matches.size());
      score.correct.assign(options.taus.size(), 0);
      for (const auto& match : judged) {
        if (!match.has_depth) ++score.no_depth;
        if (match.on_dynamic) ++score.on_dynamic;
        if (match.has_depth && !match.on_dynamic && match.error_px >= 0.0) {
          result.methods[m].errors_px.push_back(match.error_px);
        }
        for (std::size_t t = 0; t < options.taus.size(); ++t) {
          if (IsCorrect(match, options.taus[t])) ++score.correct[t];
        }
      }
      // Every method is held to the border ORB-SLAM's geometry keeps free of points, so that
      // none is counted as losing corners where it never looks.
      const Repeatability repeatability =
          MeasureRepeatability(a.keypoints, b.keypoints, geometry, options.taus,
                               static_cast<double>(features::kEdgeThreshold));
      score.comparable = repeatability.comparable;
      score.repeated = repeatability.repeated;
      result.methods[m].pairs.push_back(score);
      if (p == showcase) {
        result.methods[m].showcase =
            DrawPair(images[i].bgr, a.keypoints, images[j].bgr, b.keypoints, judged,
                     options.taus[options.taus.size() / 2]);
      }
    }
    if (progress && ((p + 1) % 40 == 0 || p + 1 == pair_starts.size())) {
      progress("matched " + std::to_string(p + 1) + "/" + std::to_string(pair_starts.size()) +
               " pairs");
    }
  }
  for (std::size_t m = 0; m < methods.size(); ++m) result.methods[m].method = methods[m]->name();

  std::vector<double> all_errors;
  for (const auto& method : result.methods) {
    all_errors.insert(all_errors.end(), method.errors_px.begin(), method.errors_px.end());
  }
  result.default_tau = ChooseTau(all_errors, options.taus);
  return result;
}

MethodSummary Summarize(const MethodScore& score, std::size_t num_taus) {
  MethodSummary summary;
  summary.mean_correct.assign(num_taus, 0.0);
  summary.rate.assign(num_taus, 0.0);
  summary.repeatability.assign(num_taus, 0.0);
  for (const auto& count : score.counts) summary.mean_count += count.count;
  if (!score.counts.empty()) summary.mean_count /= static_cast<double>(score.counts.size());
  double judged = 0.0;
  double comparable = 0.0;
  for (const auto& pair : score.pairs) {
    comparable += pair.comparable;
    for (std::size_t t = 0; t < num_taus && t < pair.repeated.size(); ++t) {
      summary.repeatability[t] += pair.repeated[t];
    }
    summary.mean_matches += pair.matches;
    summary.mean_no_depth += pair.no_depth;
    summary.mean_on_dynamic += pair.on_dynamic;
    judged += pair.matches - pair.no_depth;
    for (std::size_t t = 0; t < num_taus && t < pair.correct.size(); ++t) {
      summary.mean_correct[t] += pair.correct[t];
    }
  }
  for (std::size_t t = 0; t < num_taus; ++t) {
    summary.rate[t] = judged > 0.0 ? summary.mean_correct[t] / judged : 0.0;
    summary.repeatability[t] = comparable > 0.0 ? summary.repeatability[t] / comparable : 0.0;
  }
  if (!score.pairs.empty()) {
    const double n = static_cast<double>(score.pairs.size());
    summary.mean_matches /= n;
    summary.mean_no_depth /= n;
    summary.mean_on_dynamic /= n;
    for (auto& value : summary.mean_correct) value /= n;
  }
  return summary;
}

std::vector<double> MeanPerTenFrames(const std::vector<FrameCount>& counts) {
  std::vector<double> means;
  for (std::size_t start = 0; start < counts.size(); start += 10) {
    const std::size_t end = std::min(counts.size(), start + 10);
    double sum = 0.0;
    for (std::size_t k = start; k < end; ++k) sum += counts[k].count;
    means.push_back(sum / static_cast<double>(end - start));
  }
  return means;
}

namespace {

std::string Fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

std::size_t DefaultTauIndex(const FeatureEvalResult& result) {
  for (std::size_t t = 0; t < result.taus.size(); ++t) {
    if (result.taus[t] == result.default_tau) return t;
  }
  return 0;
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) ThrowFileError(path, "cannot write");
}

std::string Tau(double tau) { return Fixed(tau, tau == std::floor(tau) ? 0 : 1); }

}  // namespace

std::string SummaryMarkdown(const FeatureEvalResult& result) {
  const std::size_t d = DefaultTauIndex(result);
  std::ostringstream md;
  md << "| method | points/frame | matches/pair | no depth | on person | correct (τ="
     << Tau(result.default_tau) << " px) | rate | repeatability (τ=" << Tau(result.taus.front())
     << " px)";
  for (const double tau : result.taus) md << " | rate τ=" << Tau(tau);
  md << " |\n|---|---:|---:|---:|---:|---:|---:|---:";
  for (std::size_t t = 0; t < result.taus.size(); ++t) md << "|---:";
  md << "|\n";
  for (const auto& method : result.methods) {
    const MethodSummary s = Summarize(method, result.taus.size());
    md << "| " << method.method << " | " << Fixed(s.mean_count, 1) << " | "
       << Fixed(s.mean_matches, 1) << " | " << Fixed(s.mean_no_depth, 1) << " | "
       << Fixed(s.mean_on_dynamic, 1) << " | " << Fixed(s.mean_correct[d], 1) << " | "
       << Fixed(s.rate[d], 3) << " | " << Fixed(s.repeatability.front(), 3);
    for (const double rate : s.rate) md << " | " << Fixed(rate, 3);
    md << " |\n";
  }
  return md.str();
}

void WriteFeatureEvalReport(const FeatureEvalResult& result, const fs::path& dir) {
  if (!fs::is_directory(dir)) ThrowFileError(dir, "output folder does not exist");
  std::ostringstream counts, mean10, pairs, errors;
  counts << "method,frame,timestamp,count,extract_ms\n";
  mean10 << "method,first_frame,mean_count\n";
  pairs << "method,frame_i,frame_j,matches,no_depth,on_dynamic";
  for (const double tau : result.taus) pairs << ",correct_" << Tau(tau);
  pairs << ",comparable";
  for (const double tau : result.taus) pairs << ",repeated_" << Tau(tau);
  pairs << "\n";
  errors << "method,error_px\n";
  nlohmann::json json;
  json["dataset"] = result.dataset;
  json["taus"] = result.taus;
  json["default_tau"] = result.default_tau;
  for (const auto& method : result.methods) {
    for (const auto& c : method.counts) {
      counts << method.method << ',' << c.frame << ',' << Fixed(c.timestamp, 6) << ',' << c.count
             << ',' << Fixed(c.extract_ms, 2) << "\n";
    }
    const auto means = MeanPerTenFrames(method.counts);
    for (std::size_t b = 0; b < means.size(); ++b) {
      mean10 << method.method << ',' << b * 10 << ',' << Fixed(means[b], 1) << "\n";
    }
    for (const auto& p : method.pairs) {
      pairs << method.method << ',' << p.frame_i << ',' << p.frame_j << ',' << p.matches << ','
            << p.no_depth << ',' << p.on_dynamic;
      for (const int c : p.correct) pairs << ',' << c;
      pairs << ',' << p.comparable;
      for (const int r : p.repeated) pairs << ',' << r;
      pairs << "\n";
    }
    for (const double e : method.errors_px) errors << method.method << ',' << Fixed(e, 3) << "\n";
    const MethodSummary s = Summarize(method, result.taus.size());
    json["methods"].push_back({{"method", method.method},
                               {"mean_count", s.mean_count},
                               {"mean_matches", s.mean_matches},
                               {"mean_no_depth", s.mean_no_depth},
                               {"mean_on_dynamic", s.mean_on_dynamic},
                               {"mean_correct", s.mean_correct},
                               {"rate", s.rate},
                               {"repeatability", s.repeatability}});
    if (!method.showcase.empty()) {
      io::WriteImage(dir / ("matches_" + method.method + ".png"), method.showcase);
    }
  }
  WriteFile(dir / "counts.csv", counts.str());
  WriteFile(dir / "counts_mean10.csv", mean10.str());
  WriteFile(dir / "pairs.csv", pairs.str());
  WriteFile(dir / "errors.csv", errors.str());
  WriteFile(dir / "summary.json", json.dump(2) + "\n");
  std::ostringstream md;
  md << "# Feature evaluation: " << result.dataset << "\n\n"
     << "Matches of frame i against frame i+gap (ratio test); a match is correct when the point of "
        "frame i, lifted with its depth and moved by the ground-truth pose, lands within τ px of "
        "its partner. Rates are over matches with depth; matches on a moving person count as "
        "wrong. Default τ = "
     << Tau(result.default_tau)
     << " px, chosen from the error distribution. Repeatability: the share of frame i's points "
        "(with depth, static, landing inside frame j) that frame j detected again within the "
        "smallest τ, whatever the descriptors say (at larger τ a dense detector repeats by "
        "chance: 1,000 points in 640x480 leave one within 10 px of almost any pixel).\n\n"
     << SummaryMarkdown(result);
  WriteFile(dir / "summary.md", md.str());

  // Plots: one data block per method (gnuplot's index), so every method is one line or bar.
  std::ostringstream count_data, mean10_data, rate_data, repeat_data, hist_data;
  const std::size_t d = DefaultTauIndex(result);
  for (std::size_t m = 0; m < result.methods.size(); ++m) {
    const auto& method = result.methods[m];
    count_data << "# " << method.method << "\n";
    for (const auto& c : method.counts) count_data << c.frame << ' ' << c.count << "\n";
    count_data << "\n\n";
    mean10_data << "# " << method.method << "\n";
    const auto means = MeanPerTenFrames(method.counts);
    for (std::size_t b = 0; b < means.size(); ++b) mean10_data << b * 10 << ' ' << means[b] << "\n";
    mean10_data << "\n\n";
    const MethodSummary s = Summarize(method, result.taus.size());
    rate_data << '"' << method.method << '"';
    for (const double rate : s.rate) rate_data << ' ' << rate;
    rate_data << "\n";
    repeat_data << '"' << method.method << '"';
    for (const double share : s.repeatability) repeat_data << ' ' << share;
    repeat_data << "\n";
    hist_data << "# " << method.method << "\n";
    std::vector<int> bins(30, 0);
    for (const double e : method.errors_px) {
      if (e < 30.0) ++bins[static_cast<std::size_t>(e)];
    }
    for (std::size_t b = 0; b < bins.size(); ++b) hist_data << b + 0.5 << ' ' << bins[b] << "\n";
    hist_data << "\n\n";
  }
  WriteFile(dir / "counts.dat", count_data.str());
  WriteFile(dir / "counts_mean10.dat", mean10_data.str());
  WriteFile(dir / "correct_rate.dat", rate_data.str());
  WriteFile(dir / "repeatability.dat", repeat_data.str());
  WriteFile(dir / "errors.dat", hist_data.str());
  std::ostringstream titles;
  const std::size_t n = result.methods.size();
  auto per_method = [&](const std::string& file, const std::string& style) {
    std::ostringstream plot;
    plot << "plot ";
    for (std::size_t m = 0; m < n; ++m) {
      plot << (m ? ", " : "") << "'" << file << "' index " << m << " with " << style << " title '"
           << result.methods[m].method << "'";
    }
    return plot.str();
  };
  const std::string head =
      "set terminal pngcairo size 1000,560 font 'Sans,11'\nset key outside\n"
      "set grid\n";
  WriteFile(dir / "counts.gp", head +
                                   "set output 'counts.png'\nset xlabel 'frame'\n"
                                   "set ylabel 'feature points'\nset title 'Points per frame: " +
                                   result.dataset + "'\n" + per_method("counts.dat", "lines lw 2") +
                                   "\n");
  WriteFile(dir / "counts_mean10.gp",
            head +
                "set output 'counts_mean10.png'\nset xlabel 'first frame of the block'\n"
                "set ylabel 'mean points per frame'\nset title 'Mean of every 10 frames'\n" +
                per_method("counts_mean10.dat", "linespoints lw 2 pt 7") + "\n");
  WriteFile(dir / "errors.gp",
            head +
                "set output 'errors.png'\nset xlabel 'reprojection error (px)'\n"
                "set ylabel 'matches'\nset logscale y\nset title 'Error of judged matches "
                "(all pairs)'\n" +
                per_method("errors.dat", "steps lw 2") + "\n");
  // Methods along x, one bar per tau.
  // The bar of tau `marked` is labelled `mark` (the one summary.md reports).
  auto bars_per_tau = [&](const std::string& name, const std::string& ylabel,
                          const std::string& title, std::size_t marked, const std::string& mark) {
    std::ostringstream plot;
    plot << head << "set output '" << name
         << ".png'\nset style data histograms\n"
            "set style histogram clustered gap 1\nset style fill solid 0.8 border -1\n"
            "set yrange [0:1]\nset ylabel '"
         << ylabel << "'\nset xtics rotate by -30\nset title '" << title << "'\nplot ";
    for (std::size_t t = 0; t < result.taus.size(); ++t) {
      plot << (t ? ", " : "") << "'" << name << ".dat' using " << t + 2
           << (t == 0 ? ":xtic(1)" : "") << " title 'τ = " << Tau(result.taus[t]) << " px"
           << (t == marked ? " (" + mark + ")" : "") << "'";
    }
    WriteFile(dir / (name + ".gp"), plot.str() + "\n");
  };
  bars_per_tau("correct_rate", "correct-match rate", "Correct-match rate (frame i vs i+gap)", d,
               "default");
  bars_per_tau("repeatability", "share of the points found again",
               "Repeatability: points of frame i that frame i+gap detected again", 0,
               "in summary.md");
  for (const char* script :
       {"counts.gp", "counts_mean10.gp", "errors.gp", "correct_rate.gp", "repeatability.gp"}) {
    RunGnuplot(dir / script);
  }
}

}  // namespace noctua::eval
