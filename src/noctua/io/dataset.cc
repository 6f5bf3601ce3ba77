#include "noctua/io/dataset.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "noctua/io/image_file.h"
#include "noctua/io/text_list.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace fs = std::filesystem;
namespace {

// OpenLORIS without list files: the images' names are their timestamps.
std::vector<TimedFile> ListFolderByTimestamp(const fs::path& dataset, const std::string& folder) {
  std::vector<TimedFile> files;
  for (const auto& entry : fs::directory_iterator(dataset / folder)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".png") continue;
    const std::string stem = entry.path().stem().string();
    files.push_back(
        {ParseNumber(entry.path(), 0, stem), folder + "/" + entry.path().filename().string(), 0});
  }
  std::sort(files.begin(), files.end(),
            [](const TimedFile& a, const TimedFile& b) { return a.timestamp < b.timestamp; });
  return files;
}

std::vector<TimedFile> ListOrFolder(const fs::path& dataset, const std::string& list,
                                    const std::string& folder) {
  return fs::exists(dataset / list) ? ReadTimedFileList(dataset / list)
                                    : ListFolderByTimestamp(dataset, folder);
}

// Where a pair came from, for error messages: the list file and line when there is one.
[[noreturn]] void ThrowPairError(const fs::path& list, int line, const fs::path& file,
                                 const std::string& problem) {
  if (line > 0) ThrowLineError(list, line, file.string() + ": " + problem);
  ThrowFileError(file, problem);
}

}  // namespace

std::vector<TimedFile> ReadTimedFileList(const fs::path& path) {
  std::vector<TimedFile> files;
  for (const TextLine& line : ReadTextLines(path)) {
    if (line.fields.size() != 2) {
      ThrowLineError(
          path, line.number,
          "expected 'timestamp file', found " + std::to_string(line.fields.size()) + " fields");
    }
    const double timestamp = ParseNumber(path, line.number, line.fields[0]);
    // A list out of time order or with a repeated time is a damaged list, not something to
    // reorder silently.
    if (!files.empty() && !(timestamp > files.back().timestamp)) {
      ThrowLineError(path, line.number,
                     "timestamp does not increase (line " + std::to_string(files.back().line) +
                         " before it is at the same time or later)");
    }
    files.push_back({timestamp, line.fields[1], line.number});
  }
  return files;
}

std::vector<RgbdPair> ReadAssociationList(const fs::path& path) {
  std::vector<RgbdPair> pairs;
  for (const TextLine& line : ReadTextLines(path)) {
    if (line.fields.size() != 4) {
      ThrowLineError(path, line.number,
                     "expected 't_rgb rgb_file t_depth depth_file', found " +
                         std::to_string(line.fields.size()) + " fields");
    }
    pairs.push_back(
        {{ParseNumber(path, line.number, line.fields[0]), line.fields[1], line.number},
         {ParseNumber(path, line.number, line.fields[2]), line.fields[3], line.number}});
  }
  return pairs;
}

std::vector<RgbdPair> AssociateByTimestamp(const std::vector<TimedFile>& rgb,
                                           const std::vector<TimedFile>& depth, double max_dt_s) {
  std::vector<TimedFile> depth_sorted = depth;
  std::stable_sort(
      depth_sorted.begin(), depth_sorted.end(),
      [](const TimedFile& a, const TimedFile& b) { return a.timestamp < b.timestamp; });
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;  // |dt|, rgb, depth
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const auto first =
        std::lower_bound(depth_sorted.begin(), depth_sorted.end(), rgb[i].timestamp - max_dt_s,
                         [](const TimedFile& file, double time) { return file.timestamp < time; });
    for (auto it = first; it != depth_sorted.end() && it->timestamp <= rgb[i].timestamp + max_dt_s;
         ++it) {
      candidates.emplace_back(std::abs(it->timestamp - rgb[i].timestamp), i,
                              static_cast<std::size_t>(it - depth_sorted.begin()));
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> rgb_used(rgb.size(), false);
  std::vector<bool> depth_used(depth_sorted.size(), false);
  std::vector<RgbdPair> pairs;
  for (const auto& [dt, i, j] : candidates) {
    if (rgb_used[i] || depth_used[j]) continue;
    rgb_used[i] = depth_used[j] = true;
    pairs.push_back({rgb[i], depth_sorted[j]});
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const RgbdPair& a, const RgbdPair& b) { return a.rgb.timestamp < b.rgb.timestamp; });
  return pairs;
}

cv::Mat DepthToMetres(const cv::Mat& depth16, double depth_factor) {
  CheckOption(depth_factor > 0.0, "the depth factor must be positive");
  cv::Mat metres;
  depth16.convertTo(metres, CV_32F, 1.0 / depth_factor);
  return metres;
}

void SequenceOptions::Check() const {
  CheckOption(max_association_dt_s > 0.0, "max_association_dt_s must be positive");
  CheckOption(max_ground_truth_gap_s > 0.0, "max_ground_truth_gap_s must be positive");
}

Sequence Sequence::Open(const fs::path& dir, const SequenceOptions& options) {
  options.Check();
  std::error_code error;
  if (!fs::is_directory(dir, error)) ThrowFileError(dir, "no such dataset folder");

  DatasetLayout layout;
  fs::path list;  // the file errors about pairs refer to
  std::vector<RgbdPair> pairs;
  if (fs::exists(dir / "rgb.txt") || fs::exists(dir / "associations.txt")) {
    layout = DatasetLayout::kTum;
    if (fs::exists(dir / "associations.txt")) {
      list = dir / "associations.txt";
      pairs = ReadAssociationList(list);
    } else {
      list = dir / "rgb.txt";
      const auto rgb = ReadTimedFileList(list);
      const auto depth = ReadTimedFileList(dir / "depth.txt");
      if (!rgb.empty() && depth.empty()) ThrowFileError(dir / "depth.txt", "lists no depth images");
      pairs = AssociateByTimestamp(rgb, depth, options.max_association_dt_s);
    }
  } else if (fs::is_directory(dir / "color", error) &&
             fs::is_directory(dir / "aligned_depth", error)) {
    layout = DatasetLayout::kOpenLoris;
    list = fs::exists(dir / "color.txt") ? dir / "color.txt" : dir / "color";
    pairs = AssociateByTimestamp(ListOrFolder(dir, "color.txt", "color"),
                                 ListOrFolder(dir, "aligned_depth.txt", "aligned_depth"),
                                 options.max_association_dt_s);
  } else {
    ThrowFileError(dir,
                   "not a dataset folder: expected TUM RGB-D layout (rgb.txt, depth.txt) or "
                   "OpenLORIS-Scene layout (color/, aligned_depth/)");
  }
  if (pairs.empty()) {
    ThrowFileError(list, "the sequence has no frames (no colour image with a depth image within " +
                             std::to_string(options.max_association_dt_s) + " s)");
  }

  Trajectory ground_truth;
  if (fs::exists(dir / "groundtruth.txt"))
    ground_truth = CameraTrajectoryFromGroundTruth(ReadTumTrajectory(dir / "groundtruth.txt"),
                                                   options.ground_truth_convention);

  std::vector<Frame> frames;
  frames.reserve(pairs.size());
  for (const RgbdPair& pair : pairs) {
    Frame frame;
    frame.index = static_cast<int>(frames.size());
    frame.timestamp = pair.rgb.timestamp;
    frame.rgb_path = dir / pair.rgb.file;
    frame.depth_timestamp = pair.depth.timestamp;
    frame.depth_path = dir / pair.depth.file;
    for (const auto& [path, line] :
         {std::pair{frame.rgb_path, pair.rgb.line}, std::pair{frame.depth_path, pair.depth.line}}) {
      if (!fs::is_regular_file(path, error)) {
        ThrowPairError(layout == DatasetLayout::kTum && list.filename() != "associations.txt" &&
                               path == frame.depth_path
                           ? dir / "depth.txt"
                           : list,
                       line, path, "no such image file");
      }
    }
    if (!frames.empty() && !(frame.timestamp > frames.back().timestamp)) {
      ThrowPairError(list, pair.rgb.line, frame.rgb_path, "timestamp does not increase");
    }
    frame.ground_truth = ground_truth.Interpolate(frame.timestamp, options.max_ground_truth_gap_s);
    frames.push_back(std::move(frame));
  }
  return Sequence(layout, dir, std::move(frames), std::move(ground_truth));
}

FrameImages Sequence::Load(const Frame& frame, double depth_factor) const {
  FrameImages images;
  images.bgr = ReadImage8U(frame.rgb_path);
  const cv::Mat depth16 = ReadDepth16U(frame.depth_path);
  if (depth16.size() != images.bgr.size()) {
    ThrowFileError(frame.depth_path, "depth image is " + std::to_string(depth16.cols) + "x" +
                                         std::to_string(depth16.rows) + " but its colour image " +
                                         frame.rgb_path.filename().string() + " is " +
                                         std::to_string(images.bgr.cols) + "x" +
                                         std::to_string(images.bgr.rows));
  }
  images.depth_m = DepthToMetres(depth16, depth_factor);
  // RGB-D sensors measure up to ~10 m; a mean beyond kMaxPlausibleDepthM means DepthMapFactor
  // does not fit the data (e.g. 1 for millimetre depth) and every 3-D point would be wrong.
  constexpr double kMaxPlausibleDepthM = 100.0;
  const cv::Scalar mean = cv::mean(images.depth_m, depth16 > 0);
  if (mean[0] > kMaxPlausibleDepthM) {
    ThrowFileError(frame.depth_path, "mean depth " + std::to_string(mean[0]) +
                                         " m is implausible: DepthMapFactor " +
                                         std::to_string(depth_factor) +
                                         " does not fit this depth image (TUM: 5000, "
                                         "OpenLORIS: 1000)");
  }
  return images;
}

}  // namespace noctua::io
