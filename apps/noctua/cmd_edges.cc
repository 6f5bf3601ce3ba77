// noctua edges: edge maps by phase congruency and the classic detectors, and the side-by-side
// comparison panel (the paper's Figure 4 on the user's own images).
#include <spdlog/spdlog.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "noctua/edges/edge_detector.h"
#include "noctua/image/enhancement.h"
#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"
#include "noctua/util/timer.h"

namespace noctua::app {
namespace {

namespace fs = std::filesystem;

struct EdgesArgs {
  std::vector<std::string> images;
  std::vector<std::string> methods;
  std::string out = "noctua_edges";
  std::string enhance = "none";
  bool panel = true;
  bool force = false;
};

// One tile of the panel: the map (or image) in grey with its name written on a dark band.
cv::Mat Tile(const cv::Mat& gray, const std::string& label) {
  cv::Mat tile;
  cv::cvtColor(gray, tile, cv::COLOR_GRAY2BGR);
  const int band = std::max(18, tile.rows / 16);
  cv::rectangle(tile, cv::Rect(0, 0, tile.cols, band), cv::Scalar(40, 40, 40), cv::FILLED);
  cv::putText(tile, label, cv::Point(6, band - 5), cv::FONT_HERSHEY_SIMPLEX, band / 30.0,
              cv::Scalar(80, 220, 255), 1, cv::LINE_AA);
  return tile;
}

// Tiles in rows of four, padded with white tiles (the maps are black on white).
cv::Mat Panel(const std::vector<cv::Mat>& tiles) {
  constexpr int kColumns = 4;
  std::vector<cv::Mat> rows;
  for (std::size_t first = 0; first < tiles.size(); first += kColumns) {
    std::vector<cv::Mat> row;
    for (std::size_t i = first; i < first + kColumns; ++i) {
      row.push_back(i < tiles.size()
                        ? tiles[i]
                        : cv::Mat(tiles[0].size(), tiles[0].type(), cv::Scalar::all(255)));
    }
    cv::Mat joined;
    cv::hconcat(row, joined);
    rows.push_back(joined);
  }
  cv::Mat panel;
  cv::vconcat(rows, panel);
  return panel;
}

void RunEdges(const EdgesArgs& args) {
  std::vector<edges::EdgeMethod> methods;
  for (const std::string& name : args.methods) methods.push_back(edges::ParseEdgeMethod(name));
  if (methods.empty()) methods = edges::AllEdgeMethods();
  image::EnhancementOptions enhancement;
  enhancement.method = image::ParseEnhancementMethod(args.enhance);
  const image::Enhancer enhancer(enhancement);
  std::vector<std::unique_ptr<edges::EdgeDetector>> detectors;
  for (edges::EdgeMethod method : methods) {
    edges::EdgeDetectorOptions options;
    options.method = method;
    detectors.push_back(edges::CreateEdgeDetector(options));
  }
  // The panel compares every method on the first image, whatever --method chose.
  std::vector<std::unique_ptr<edges::EdgeDetector>> panel_detectors;
  if (args.panel) {
    for (edges::EdgeMethod method : edges::AllEdgeMethods()) {
      edges::EdgeDetectorOptions options;
      options.method = method;
      panel_detectors.push_back(edges::CreateEdgeDetector(options));
    }
  }

  const fs::path out(args.out);
  io::PrepareOutputDir(out, args.force);
  nlohmann::json summary = {{"enhancement", args.enhance}, {"images", nlohmann::json::array()}};
  for (std::size_t i = 0; i < args.images.size(); ++i) {
    const fs::path path(args.images[i]);
    const cv::Mat gray = enhancer.Apply(image::ToGray8U(io::ReadImage8U(path)));
    // Index prefix: two inputs with one file name never overwrite each other.
    const std::string stem = std::to_string(i) + "_" + path.stem().string();
    nlohmann::json entry = {{"image", path.string()}, {"width", gray.cols}, {"height", gray.rows}};
    for (std::size_t m = 0; m < detectors.size(); ++m) {
      const std::string name = edges::ToString(methods[m]);
      Stopwatch watch;
      const cv::Mat edge_map = detectors[m]->Detect(gray);
      const double ms = watch.ElapsedMs();
      const fs::path file = out / (stem + "_" + name + ".png");
      io::WriteImage(file, edge_map);
      entry["methods"][name] = {
          {"file", file.filename().string()},
          {"edge_fraction", cv::countNonZero(edge_map) / static_cast<double>(edge_map.total())},
          {"ms", ms}};
    }
    if (args.panel && i == 0) {
      std::vector<cv::Mat> tiles = {Tile(gray, args.enhance == "none" ? "input" : args.enhance)};
      for (const auto& detector : panel_detectors) {
        // Edges in black on white, as printed figures show them.
        cv::Mat inverted = 255 - detector->Detect(gray);
        tiles.push_back(Tile(inverted, edges::ToString(detector->options().method)));
      }
      const fs::path file = out / (stem + "_panel.png");
      io::WriteImage(file, Panel(tiles));
      summary["panel"] = file.filename().string();
    }
    summary["images"].push_back(entry);
    spdlog::info("edges: {}/{} {}", i + 1, args.images.size(), path.string());
  }
  io::WriteTextFileAtomically(out / "edges.json", summary.dump(2) + "\n");
  spdlog::info("edges: wrote {} edge maps{} to {}", args.images.size() * detectors.size(),
               args.panel ? " and the comparison panel" : "", out.string());
}

}  // namespace

void AddEdgesCommand(CLI::App& app) {
  auto args = std::make_shared<EdgesArgs>();
  CLI::App* command = app.add_subcommand(
      "edges",
      "Edge maps by phase congruency (pc: phasecong3 reference, pc-fast: the real-time variant) "
      "and the classic detectors (canny, sobel, prewitt, roberts), with a side-by-side panel of "
      "all methods for the first image");
  command->add_option("images", args->images, "Input images (8-bit, colour or grey)")
      ->required()
      ->check(CLI::ExistingFile);
  command
      ->add_option("-m,--method", args->methods,
                   "Method(s): pc, pc-fast, canny, sobel, prewitt, roberts (default: all)")
      ->delimiter(',');
  command->add_option("-o,--out", args->out, "Output folder")->capture_default_str();
  command
      ->add_option("--enhance", args->enhance,
                   "Enhancement before edge detection: none, he, clahe (the extractor uses clahe)")
      ->capture_default_str();
  command->add_flag("!--no-panel", args->panel, "Do not write the comparison panel");
  command->add_flag("-f,--force", args->force, "Write into a non-empty output folder");
  command->callback([args] { RunEdges(*args); });
}

}  // namespace noctua::app
