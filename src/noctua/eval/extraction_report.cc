#include "noctua/eval/extraction_report.h"

#include <opencv2/imgproc.hpp>

#include "noctua/features/keypoint_overlay.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"

namespace noctua::eval {

nlohmann::json StatsToJson(const features::ExtractionStats& stats) {
  nlohmann::json json;
  json["counts"] = {{"detected", stats.detected},           {"after_mask", stats.after_mask},
                    {"after_dynamic", stats.after_dynamic}, {"after_edge", stats.after_edge},
                    {"after_nms", stats.after_nms},         {"final", stats.final_count},
                    {"edge_fill", stats.edge_fill}};
  json["stages_ran"] = stats.stages_ran;
  json["stages_skipped"] = stats.stages_skipped;
  json["stage_ms"] = stats.stage_ms;
  json["total_ms"] = stats.total_ms;
  return json;
}

std::string StageCountsLine(const features::ExtractionStats& stats) {
  return "detected " + std::to_string(stats.detected) + " -> dynamic " +
         std::to_string(stats.after_dynamic) + " -> edge " + std::to_string(stats.after_edge) +
         " -> nms " + std::to_string(stats.after_nms) + " -> final " +
         std::to_string(stats.final_count) +
         (stats.edge_fill > 0 ? " (" + std::to_string(stats.edge_fill) + " of them edge fill)"
                              : "");
}

NextExtractionImage ImageFiles(std::vector<std::filesystem::path> paths) {
  return [paths = std::move(paths),
          next = std::size_t{0}]() mutable -> std::optional<ExtractionImage> {
    if (next >= paths.size()) return std::nullopt;
    const std::filesystem::path& path = paths[next++];
    ExtractionImage image;
    image.name = path.string();
    image.stem = path.stem().string();
    image.image = io::ReadImage8U(path);
    return image;
  };
}

NextExtractionImage SourceImages(io::FrameSource& source) {
  return [&source]() -> std::optional<ExtractionImage> {
    std::optional<io::SourceFrame> frame = source.Next();
    if (!frame) return std::nullopt;
    ExtractionImage image;
    image.stem = cv::format("%.6f", frame->timestamp);
    image.name =
        source.Describe() + ", frame " + std::to_string(frame->index) + " (" + image.stem + " s)";
    image.image = std::move(frame->images.bgr);
    image.frame = frame->index;
    image.timestamp = frame->timestamp;
    return image;
  };
}

namespace {

std::string SizeText(const cv::Mat& image) {
  return std::to_string(image.cols) + "x" + std::to_string(image.rows);
}

}  // namespace

nlohmann::json ExtractToFolder(pipeline::FeatureMethod& method, const NextExtractionImage& next,
                               const ExtractionOutput& output,
                               const ExtractionCallbacks& callbacks) {
  nlohmann::json summary;
  summary["method"] = method.name();
  if (!output.source.empty()) summary["source"] = output.source;
  summary["images"] = nlohmann::json::array();
  bool reported_skips = false;
  while (std::optional<ExtractionImage> item = next()) {
    const cv::Mat& image = item->image;
    if (!output.mask.empty() && output.mask.size() != image.size()) {
      throw Error(output.mask_name + ": mask is " + SizeText(output.mask) + " but " + item->name +
                  " is " + SizeText(image));
    }
    features::Extraction result;
    try {
      result = method.Run(image, output.mask);
    } catch (const Error& error) {
      throw Error(item->name + ": " + error.what());
    }
    if (!reported_skips && !result.stats.stages_skipped.empty()) {
      for (const auto& skipped : result.stats.stages_skipped) {
        if (callbacks.on_note) callbacks.on_note(method.name() + ": stage skipped: " + skipped);
      }
      reported_skips = true;
    }
    const std::string overlay = item->stem + "_" + method.name() + ".png";
    const std::string caption = method.name() + ": " + std::to_string(result.keypoints.size()) +
                                " points, " + cv::format("%.1f ms", result.stats.total_ms);
    io::WriteImage(output.dir / overlay,
                   features::DrawKeypointsByLevel(image, result.keypoints, caption));

    nlohmann::json entry = StatsToJson(result.stats);
    entry["image"] = item->name;
    if (item->frame) entry["frame"] = *item->frame;
    if (item->timestamp) entry["timestamp"] = *item->timestamp;
    entry["keypoints"] = result.keypoints.size();
    entry["overlay"] = overlay;
    summary["images"].push_back(entry);
    if (callbacks.on_image) {
      callbacks.on_image(item->name + ": " + std::to_string(result.keypoints.size()) + " points (" +
                         StageCountsLine(result.stats) + "), " +
                         cv::format("%.1f ms", result.stats.total_ms));
    }
  }
  if (summary["images"].empty()) throw Error("extract: no image to extract from");
  io::WriteTextFileAtomically(output.dir / "summary.json", summary.dump(2) + "\n");
  return summary;
}

}  // namespace noctua::eval
