#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "noctua/features/extractor.h"
#include "noctua/io/frame_source.h"
#include "noctua/pipeline/method.h"

namespace noctua::eval {

// One frame's extraction as JSON: counts after each stage, stages that ran or were skipped, and
// milliseconds per stage.
nlohmann::json StatsToJson(const features::ExtractionStats& stats);

// "detected 2140 -> dynamic 2140 -> edge 905 -> nms 870 -> final 812" for logs and tables.
std::string StageCountsLine(const features::ExtractionStats& stats);

// One image to extract from, as `noctua extract` names it.
struct ExtractionImage {
  std::string name;  // in messages and summary.json's "image": the file, or the source's frame
  std::string stem;  // the overlay is <stem>_<method>.png
  cv::Mat image;     // 8-bit grey or BGR
  std::optional<int> frame;         // a source's frames: the position in the source
  std::optional<double> timestamp;  // and the colour image's time, seconds
};

// The next image; none after the last. Throws noctua::Error naming what it cannot read.
using NextExtractionImage = std::function<std::optional<ExtractionImage>()>;

// Image files in the given order, each read when its turn comes; the stem is the file's.
NextExtractionImage ImageFiles(std::vector<std::filesystem::path> paths);

// The colour images of a frame source (a folder, a bag) in its order. The stem is the time
// with 6 decimals, which is the file name of a TUM folder's colour image: a folder and a bag
// of the same frames give the same overlay names. The source must outlive the function.
NextExtractionImage SourceImages(io::FrameSource& source);

// Where `ExtractToFolder` writes and what it leaves out.
struct ExtractionOutput {
  std::filesystem::path dir;  // must exist (io::PrepareOutputDir)
  cv::Mat mask;               // exclusion mask (non-zero: no point) of the images' size, or empty
  std::string mask_name;      // the mask's file, for messages
  std::string source;         // summary.json's "source" when not empty (e.g. "bag run.bag")
};

// What `ExtractToFolder` tells as it goes.
struct ExtractionCallbacks {
  std::function<void(const std::string&)> on_image;  // "NAME: N points (stage counts), T ms"
  std::function<void(const std::string&)> on_note;   // e.g. the stages the method skipped
};

// Runs `method` on every image `next` gives: writes the overlay <stem>_<method>.png of each
// (colour = pyramid level) and summary.json (the method, and per image its name, keypoints,
// overlay and StatsToJson) into `output.dir`. Returns the summary; its "images" array has one
// entry per image. Throws noctua::Error naming the image for a mask of another size, an image
// the method refuses, and no image at all.
nlohmann::json ExtractToFolder(pipeline::FeatureMethod& method, const NextExtractionImage& next,
                               const ExtractionOutput& output,
                               const ExtractionCallbacks& callbacks = {});

}  // namespace noctua::eval
