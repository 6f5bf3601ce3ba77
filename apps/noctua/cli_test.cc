// End-to-end checks of the noctua command: exit codes, one-line errors and the files it writes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/version.h"

namespace {

using ::testing::HasSubstr;

using noctua::app::testing::CommandResult;
using noctua::app::testing::RunNoctua;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_ =
      std::filesystem::temp_directory_path() / ("noctua_cli_test_" + std::to_string(::getpid()));
};

TEST_F(CliTest, VersionPrintsTheProjectVersion) {
  const CommandResult result = RunNoctua("--version");
  EXPECT_EQ(result.exit_code, 0);
  EXPECT_EQ(result.output, std::string(NOCTUA_VERSION_STRING) + "\n");
}

TEST_F(CliTest, DemoWritesOverlaysAndASummaryAndCanBeRunAgain) {
  const auto out = dir_ / "demo";
  const CommandResult first = RunNoctua("demo --out " + out.string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_THAT(first.output, HasSubstr("| dark-15pct | paper |"));
  EXPECT_TRUE(std::filesystem::exists(out / "summary.md"));
  EXPECT_TRUE(std::filesystem::exists(out / "overlay_dark-15pct_paper.png"));
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  ASSERT_EQ(summary.size(), 8u);
  for (const auto& entry : summary) {
    if (entry["method"] == "paper") {
      EXPECT_EQ(entry["points_on_person"], 0);
    }
  }
  // Its own earlier output is not "a user's folder": a second run overwrites it.
  EXPECT_EQ(RunNoctua("demo --out " + out.string()).exit_code, 0);
}

TEST_F(CliTest, ExtractWritesOneOverlayPerImageAndStageCounts) {
  const auto frames = noctua::testing::Fr1RgbPaths(2);
  const auto out = dir_ / "extract";
  const CommandResult result =
      RunNoctua("extract " + frames[0].string() + " " + frames[1].string() +
                " --method clahe-orb --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["method"], "clahe-orb");
  ASSERT_EQ(summary["images"].size(), 2u);
  for (const auto& image : summary["images"]) {
    EXPECT_GT(image["keypoints"].get<int>(), 500);
    EXPECT_GE(image["counts"]["detected"].get<int>(), image["counts"]["final"].get<int>());
    EXPECT_TRUE(image["stage_ms"].contains("fast"));
    EXPECT_TRUE(std::filesystem::exists(out / image["overlay"].get<std::string>()));
  }
}

TEST_F(CliTest, PaperSaysWhichStagesRan) {
  const auto frame = noctua::testing::Fr1RgbPaths(1)[0];
  const auto out = dir_ / "paper";
  const CommandResult result = RunNoctua("extract " + frame.string() + " --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  const auto& image = summary["images"][0];
  EXPECT_THAT(image["stages_ran"].dump(), HasSubstr("nms-filter"));
  EXPECT_THAT(image["stages_ran"].dump() + image["stages_skipped"].dump(),
              HasSubstr("edge-filter"));
}

TEST_F(CliTest, BadInputFailsWithAOneLineReason) {
  const auto missing =
      RunNoctua("extract " + (dir_ / "absent.png").string() + " --out " + (dir_ / "o1").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("absent.png: no such file"));

  const auto corrupt = dir_ / "corrupt.png";
  std::ofstream(corrupt) << "not a png";
  const auto bad = RunNoctua("extract " + corrupt.string() + " --out " + (dir_ / "o2").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_THAT(bad.output, HasSubstr("corrupt.png: cannot decode"));

  const auto frame = noctua::testing::Fr1RgbPaths(1)[0];
  const auto small_mask = dir_ / "mask.png";
  cv::imwrite(small_mask.string(), cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
  const auto mismatch = RunNoctua("extract " + frame.string() + " --mask " + small_mask.string() +
                                  " --out " + (dir_ / "o3").string());
  EXPECT_EQ(mismatch.exit_code, 1);
  EXPECT_THAT(mismatch.output, HasSubstr("mask is 10x10"));

  const auto unknown =
      RunNoctua("extract " + frame.string() + " --method akaze --out " + (dir_ / "o4").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("unknown method 'akaze'"));

  const auto depth16 = dir_ / "depth16.png";
  cv::imwrite(depth16.string(), cv::Mat(480, 640, CV_16UC1, cv::Scalar(1000)));
  const auto sixteen =
      RunNoctua("extract " + depth16.string() + " --out " + (dir_ / "o5").string());
  EXPECT_EQ(sixteen.exit_code, 1);
  EXPECT_THAT(sixteen.output, HasSubstr("expected an 8-bit image"));
}

TEST_F(CliTest, ExistingOutputFolderIsNotOverwrittenWithoutForce) {
  const auto out = dir_ / "taken";
  std::filesystem::create_directories(out);
  std::ofstream(out / "precious.txt") << "mine";
  const auto frame = noctua::testing::Fr1RgbPaths(1)[0];
  const auto refused = RunNoctua("extract " + frame.string() + " --out " + out.string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_THAT(refused.output, HasSubstr("--force"));
  EXPECT_EQ(RunNoctua("extract " + frame.string() + " --force --out " + out.string()).exit_code, 0);
  EXPECT_TRUE(std::filesystem::exists(out / "precious.txt"));
}

TEST_F(CliTest, EdgesWritesOneMapPerMethodAndThePanel) {
  const auto frame = noctua::testing::Fr1RgbPaths(1)[0];
  const auto out = dir_ / "edges";
  const CommandResult result =
      RunNoctua("edges " + frame.string() + " --method pc-fast,canny --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string stem = "0_" + frame.stem().string();
  for (const char* method : {"pc-fast", "canny"}) {
    const cv::Mat map =
        cv::imread((out / (stem + "_" + method + ".png")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(map.type(), CV_8UC1) << method;
    EXPECT_EQ(map.size(), cv::Size(640, 480)) << method;
    EXPECT_GT(cv::countNonZero(map), 1000) << method;
  }
  EXPECT_FALSE(std::filesystem::exists(out / (stem + "_sobel.png")));
  // The panel shows the input and all six methods, four tiles a row.
  const cv::Mat panel = cv::imread((out / (stem + "_panel.png")).string());
  EXPECT_EQ(panel.size(), cv::Size(4 * 640, 2 * 480));
  std::ifstream in(out / "edges.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_GT(summary["images"][0]["methods"]["pc-fast"]["edge_fraction"].get<double>(), 0.001);

  const auto unknown =
      RunNoctua("edges " + frame.string() + " --method laplace --out " + (dir_ / "e2").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("unknown edge method 'laplace'"));
  const auto tiny = dir_ / "tiny.png";
  cv::imwrite(tiny.string(), cv::Mat(8, 8, CV_8UC1, cv::Scalar(0)));
  const auto small =
      RunNoctua("edges " + tiny.string() + " --method pc --out " + (dir_ / "e3").string());
  EXPECT_EQ(small.exit_code, 1);
  EXPECT_THAT(small.output, HasSubstr("smaller than the minimum"));
}

TEST_F(CliTest, DetectWritesOverlayMaskAndJsonAndNamesABadModel) {
  const auto models = noctua::testing::ModelsDir();
  const auto bus = models / "images" / "bus.jpg";
  const auto out = dir_ / "detect";
  const CommandResult result = RunNoctua("detect " + bus.string() + " --model " +
                                         (models / "yolov8n" / "yolov8n_head_f32.onnx").string() +
                                         " --input 480x640 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "detect.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["kind"], "yolov8-head");
  ASSERT_EQ(summary["images"].size(), 1u);
  const auto& image = summary["images"][0];
  int people = 0;
  for (const auto& d : image["detections"]) {
    if (d["class"] == "person") {
      ++people;
      EXPECT_EQ(d["motion_level"], "high");
      EXPECT_TRUE(d["dynamic"].get<bool>());
    }
    if (d["class"] == "bus") {
      EXPECT_FALSE(d["dynamic"].get<bool>());
    }
  }
  EXPECT_EQ(people, 4);
  EXPECT_GT(image["dynamic_fraction"].get<double>(), 0.1);
  const cv::Mat overlay = cv::imread((out / image["overlay"].get<std::string>()).string());
  EXPECT_EQ(overlay.size(), cv::Size(810, 1080));
  const cv::Mat mask =
      cv::imread((out / image["mask"].get<std::string>()).string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(mask.type(), CV_8UC1);

  const auto missing = RunNoctua("detect " + bus.string() + " --model /nonexistent/m.onnx --out " +
                                 (dir_ / "d2").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("/nonexistent/m.onnx: detector model not found"));
  const auto bad_size = RunNoctua("detect " + bus.string() + " --model /x.onnx --input 300x200");
  EXPECT_EQ(bad_size.exit_code, 1);
  EXPECT_THAT(bad_size.output, HasSubstr("multiple of 32"));
}

TEST_F(CliTest, HelpExitsZeroForEveryCommand) {
  EXPECT_EQ(RunNoctua("--help").exit_code, 0);
  EXPECT_EQ(RunNoctua("demo --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("extract --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("edges --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("simulate --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("eval --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("detect --help").exit_code, 0);
  EXPECT_EQ(RunNoctua("vocab --help").exit_code, 0);
  EXPECT_NE(RunNoctua("").exit_code, 0);
}

// A small vocabulary from 6 frames of a sequence folder: the same bytes twice (fixed seed), k^L
// words at most; a folder without images is refused naming it.
TEST_F(CliTest, VocabTrainsTheSameFileTwiceAndRefusesAFolderWithoutImages) {
  const std::string bonn = (noctua::testing::DataDir() / "bonn_crowd_120").string();
  std::string first;
  for (const char* name : {"a.vocab", "b.vocab"}) {
    const auto out = dir_ / name;
    const CommandResult trained =
        RunNoctua("vocab " + bonn + " --max-images 6 --k 4 --levels 2 " + "--out " + out.string());
    ASSERT_EQ(trained.exit_code, 0) << trained.output;
    EXPECT_THAT(trained.output, HasSubstr("16 words (k 4, L 2) from 6 images"));
    std::ifstream in(out, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (first.empty()) {
      first = bytes;
    } else {
      EXPECT_EQ(bytes, first);
    }
  }
  std::filesystem::create_directories(dir_ / "empty");
  const CommandResult empty =
      RunNoctua("vocab " + (dir_ / "empty").string() + " --out " + (dir_ / "e.vocab").string());
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_THAT(empty.output, HasSubstr((dir_ / "empty").string() + ": holds no image"));
}

TEST_F(CliTest, SimulateThenEvalWriteATumSequenceAndTheReport) {
  const std::string fr1 = (noctua::testing::DataDir() / "tum_fr1_rpy_200").string();
  const auto sequence = dir_ / "dark";
  const CommandResult simulated = RunNoctua(
      "simulate --dataset " + fr1 + " --camera " + NOCTUA_SOURCE_DIR +
      "/config/tum_fr1.yaml --level 30 --person --max-frames 12 --out " + sequence.string());
  ASSERT_EQ(simulated.exit_code, 0) << simulated.output;
  for (const char* file : {"rgb.txt", "depth.txt", "associations.txt", "groundtruth.txt",
                           "camera.yaml", "simulation.json"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(sequence / file)) << file;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(sequence / "mask"),
                          std::filesystem::directory_iterator()),
            12);
  const auto report = dir_ / "report";
  const CommandResult evaluated = RunNoctua("eval --dataset " + sequence.string() +
                                            " --methods orb,sift --gap 5 --out " + report.string());
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.output;
  EXPECT_THAT(evaluated.output, HasSubstr("| sift |"));
  for (const char* file : {"summary.md", "counts.csv", "pairs.csv", "counts.png",
                           "correct_rate.png", "repeatability.png", "matches_orb.png"}) {
    EXPECT_TRUE(std::filesystem::is_regular_file(report / file)) << file;
  }
  // Bad input: an unknown method and a folder without ground truth, each with a one-line reason.
  const CommandResult unknown = RunNoctua("eval --dataset " + sequence.string() +
                                          " --methods orb,nope --out " + (dir_ / "x").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("unknown method 'nope'"));
  std::filesystem::remove(sequence / "groundtruth.txt");
  const CommandResult no_truth = RunNoctua("eval --dataset " + sequence.string() +
                                           " --methods orb --out " + (dir_ / "y").string());
  EXPECT_EQ(no_truth.exit_code, 1);
  EXPECT_THAT(no_truth.output, HasSubstr("groundtruth"));
}

TEST_F(CliTest, SimulateListsTheSensorModelsAndRefusesAnUnknownOne) {
  const CommandResult listed = RunNoctua("simulate --list-sensors");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  for (const char* name : {"| webcam |", "| kinect |", "| d435 |", "| large-pixel |"}) {
    EXPECT_THAT(listed.output, HasSubstr(name));
  }
  const std::string fr1 = (noctua::testing::DataDir() / "tum_fr1_rpy_200").string();
  const CommandResult unknown =
      RunNoctua("simulate --dataset " + fr1 + " --camera " + NOCTUA_SOURCE_DIR +
                "/config/tum_fr1.yaml --level 15 --sensor potato --out " + (dir_ / "p").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("unknown sensor model 'potato'"));
  const CommandResult too_short = RunNoctua(
      "simulate --dataset " + fr1 + " --camera " + NOCTUA_SOURCE_DIR +
      "/config/tum_fr1.yaml --level 15 --max-exposure-ms 2 --out " + (dir_ / "s").string());
  EXPECT_EQ(too_short.exit_code, 1);
  EXPECT_THAT(too_short.output, HasSubstr("max_exposure_s must be at least exposure_s"));
  const CommandResult no_dataset = RunNoctua("simulate --level 15 --out " + (dir_ / "q").string());
  EXPECT_EQ(no_dataset.exit_code, 1);
  EXPECT_THAT(no_dataset.output, HasSubstr("simulate needs --dataset"));
}

TEST_F(CliTest, SimulateCompositesARealPersonCutOutGivenByAMaskOrFoundByTheSegmenter) {
  const std::string fr1 = (noctua::testing::DataDir() / "tum_fr1_rpy_200").string();
  const std::string camera = std::string(NOCTUA_SOURCE_DIR) + "/config/tum_fr1.yaml";
  const auto fr3 =
      noctua::testing::DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb" / "1341846648.438342.png";
  // A hand-made mask: a rectangle standing for the person.
  const auto mask = dir_ / "person_mask.png";
  cv::Mat mask_image = cv::Mat::zeros(480, 640, CV_8UC1);
  mask_image(cv::Rect(340, 20, 150, 440)).setTo(255);
  ASSERT_TRUE(cv::imwrite(mask.string(), mask_image));
  const std::string base = "simulate --dataset " + fr1 + " --camera " + camera +
                           " --max-frames 6 --person-distance 0.5 --person-cutout " + fr3.string();
  const auto with_mask = dir_ / "with_mask";
  const CommandResult masked =
      RunNoctua(base + " --person-mask " + mask.string() + " --out " + with_mask.string());
  ASSERT_EQ(masked.exit_code, 0) << masked.output;
  int most_covered = 0;  // the walk crosses the view: some frame shows much of the person
  for (const auto& entry : std::filesystem::directory_iterator(with_mask / "mask")) {
    const cv::Mat person_mask = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(person_mask.empty()) << entry.path();
    most_covered = std::max(most_covered, cv::countNonZero(person_mask));
  }
  EXPECT_GT(most_covered, 10000);

  const auto segmented = dir_ / "segmented";
  const CommandResult found = RunNoctua(
      base + " --seg-model " +
      (noctua::testing::ModelsDir() / "yolov8n-seg" / "yolov8n-seg_head_f32.onnx").string() +
      " --out " + segmented.string());
  ASSERT_EQ(found.exit_code, 0) << found.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(segmented / "simulation.json"));

  // Bad input, each with a one-line reason.
  const CommandResult both_missing = RunNoctua(base + " --out " + (dir_ / "a").string());
  EXPECT_EQ(both_missing.exit_code, 1);
  EXPECT_THAT(both_missing.output, HasSubstr("exactly one of --person-mask and --seg-model"));
  const auto small = dir_ / "small_mask.png";
  ASSERT_TRUE(cv::imwrite(small.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  const CommandResult wrong_size =
      RunNoctua(base + " --person-mask " + small.string() + " --out " + (dir_ / "b").string());
  EXPECT_EQ(wrong_size.exit_code, 1);
  EXPECT_THAT(wrong_size.output, HasSubstr("small_mask.png: person mask is not of the cut-out"));
  const auto empty = dir_ / "empty_mask.png";
  ASSERT_TRUE(cv::imwrite(empty.string(), cv::Mat::zeros(480, 640, CV_8UC1)));
  const CommandResult empty_mask =
      RunNoctua(base + " --person-mask " + empty.string() + " --out " + (dir_ / "c").string());
  EXPECT_EQ(empty_mask.exit_code, 1);
  EXPECT_THAT(empty_mask.output, HasSubstr("empty_mask.png: person mask is empty"));
  const CommandResult not_seg =
      RunNoctua(base + " --seg-model " +
                (noctua::testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx").string() +
                " --out " + (dir_ / "d").string());
  EXPECT_EQ(not_seg.exit_code, 1);
  EXPECT_THAT(not_seg.output, HasSubstr("not a segmentation model"));
}

// Every number in a bench row must be a positive measurement; timings themselves are never
// asserted.
void ExpectPositiveRow(const nlohmann::json& row) {
  for (const char* key :
       {"median_ms", "spread_min_ms", "spread_max_ms", "ratio_to_orb_opencv", "samples"}) {
    ASSERT_TRUE(row.contains(key)) << row["name"] << " " << key;
    EXPECT_GT(row[key].get<double>(), 0.0) << row["name"] << " " << key;
  }
  EXPECT_LE(row["spread_min_ms"].get<double>(), row["spread_max_ms"].get<double>()) << row["name"];
}

TEST_F(CliTest, BenchWritesATableJsonAndPlotWithEveryStageAndMethod) {
  const auto out = dir_ / "bench";
  const CommandResult result = RunNoctua("bench --frames 3 --repeat 1 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "bench.json");
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["frames"], 3);
  EXPECT_EQ(report["repeat"], 1);
  EXPECT_GT(report["reference"]["median_ms"].get<double>(), 0.0);
  std::vector<std::string> methods;
  for (const auto& row : report["methods"]) {
    methods.push_back(row["name"]);
    ExpectPositiveRow(row);
    EXPECT_GT(row["frames_per_s"].get<double>(), 0.0);
  }
  EXPECT_THAT(methods,
              ::testing::IsSupersetOf({"fast", "orb-opencv", "orb", "he-orb", "clahe-orb", "paper",
                                       "noctua", "sift", "surf", "slam (paper)"}));
  std::vector<std::string> stages;
  for (const auto& row : report["stages"]) {
    stages.push_back(row["name"]);
    ExpectPositiveRow(row);
  }
  EXPECT_THAT(stages,
              ::testing::IsSupersetOf(
                  {"grey conversion", "CLAHE", "pyramid (8 levels)",
                   "oFAST (grid FAST, all levels)", "orientation (intensity centroid)",
                   "phase congruency edge map", "filter (b): on an edge", "filter (c): 3x3 NMS",
                   "rBRIEF descriptors", "matching (2-NN + ratio 0.8, consecutive frames)",
                   "slam: track local map (incl. pose optimisation)",
                   // noctua's own stages: its frame conditioning changes what FAST and rBRIEF see
                   "noctua: noise conditioning (gain, noise estimate, smoothing)",
                   "noctua: oFAST (grid FAST, all levels)", "noctua: rBRIEF descriptors"}));
  // The Markdown table has one row per JSON row, and the plot is a real PNG.
  std::ifstream markdown_in(out / "bench.md");
  const std::string markdown((std::istreambuf_iterator<char>(markdown_in)),
                             std::istreambuf_iterator<char>());
  for (const auto& name : methods) EXPECT_THAT(markdown, HasSubstr("| " + name + " | "));
  for (const auto& name : stages) EXPECT_THAT(markdown, HasSubstr("| " + name + " | "));
  const cv::Mat plot = cv::imread((out / "bench.png").string());
  EXPECT_GT(plot.cols, 100);
  // Its results are not overwritten without --force.
  const CommandResult again = RunNoctua("bench --frames 3 --repeat 1 --out " + out.string());
  EXPECT_EQ(again.exit_code, 1);
  const CommandResult bad = RunNoctua("bench --frames 1 --out " + (dir_ / "b1").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_THAT(bad.output, HasSubstr("--frames"));
}

// The SLAM report carries peak memory and the map size, and frames.csv the memory and map size
// after every frame, so that growth can be set against the map.
TEST_F(CliTest, SlamReportsMemoryAndMapSize) {
  const auto out = dir_ / "slam";
  const CommandResult result = RunNoctua(
      "slam --dataset " + (noctua::testing::DataDir() / "tum_fr1_rpy_200").string() + " --config " +
      std::string(NOCTUA_SOURCE_DIR) +
      "/config/tum_fr1.yaml --method orb --max-frames 12 --deterministic --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "report.json");
  const auto report = nlohmann::json::parse(in);
  const auto& memory = report["memory"];
  EXPECT_GT(memory["peak_rss_mb"].get<double>(), 10.0);
  // The kernel's peak counter lags the current one by a few pages per thread.
  EXPECT_GE(memory["peak_rss_mb"].get<double>(), memory["final_rss_mb"].get<double>() - 5.0);
  EXPECT_EQ(memory["keyframes"], report["keyframes"]);
  EXPECT_EQ(memory["map_points"], report["map_points"]);
  EXPECT_GT(report["map_points"].get<int>(), 100);
  std::ifstream csv(out / "frames.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_THAT(line, HasSubstr(",keyframes,map_points,rss_mb,"));
  int rows = 0;
  std::string last;
  while (std::getline(csv, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, 12);
  // The last row's map size is the report's (deterministic: no mapping stage was left to run after
  // the last frame): columns 11 and 12 (keyframes, map_points); a tracked
  // frame's moving keypoints in column 6 (none: rejection is off by default), its confidence
  // in columns 7 and 8 (position sigma in mm, rotation sigma in degrees) and its fit in column 9
  // (median reprojection error, pixels of the keypoints' levels).
  std::vector<std::string> cells;
  std::stringstream cells_in(last);
  for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
  ASSERT_GT(cells.size(), 13u);
  EXPECT_EQ(cells[2], "ok");
  EXPECT_EQ(cells[6], "0");
  EXPECT_GT(std::stod(cells[7]), 0.0);
  EXPECT_LT(std::stod(cells[7]), 20.0);
  EXPECT_GT(std::stod(cells[8]), 0.0);
  EXPECT_GT(std::stod(cells[9]), 0.1);
  EXPECT_LT(std::stod(cells[9]), 3.0);
  EXPECT_EQ(std::stoi(cells[11]), report["keyframes"].get<int>());
  EXPECT_EQ(std::stoi(cells[12]), report["map_points"].get<int>());
  EXPECT_GT(std::stod(cells[13]), 10.0);
}

// With a detector, the SLAM detects on a thread of its own every N-th frame by default, says so in
// its report, and refuses contradictory detection flags.
TEST_F(CliTest, SlamDetectsAheadOnItsOwnThreadUnlessToldToDetectInline) {
  const std::string base =
      "slam --dataset " + (noctua::testing::DataDir() / "tum_fr1_rpy_200").string() + " --config " +
      std::string(NOCTUA_SOURCE_DIR) +
      "/config/tum_fr1.yaml --method paper --max-frames 8 --detector " +
      (noctua::testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx").string();
  for (const std::string mode : {"--detect-every 2", "--detect-inline"}) {
    SCOPED_TRACE(mode);
    const auto out = dir_ / ("slam" + std::to_string(mode.size()));
    const CommandResult result = RunNoctua(base + " " + mode + " --out " + out.string());
    ASSERT_EQ(result.exit_code, 0) << result.output;
    std::ifstream in(out / "report.json");
    const auto report = nlohmann::json::parse(in);
    EXPECT_EQ(report["tracked_frames"], 8);
    const bool ahead = mode != "--detect-inline";
    EXPECT_EQ(report["detection"]["every_n_frames"], ahead ? 2 : 1);
    EXPECT_THAT(report["detection"]["mode"].get<std::string>(),
                HasSubstr(ahead ? "own thread" : "inline"));
  }
  const CommandResult both =
      RunNoctua(base + " --detect-inline --detect-every 2 --out " + (dir_ / "both").string());
  EXPECT_NE(both.exit_code, 0);
  EXPECT_THAT(both.output, HasSubstr("excludes"));
  const CommandResult zero =
      RunNoctua(base + " --detect-every 0 --out " + (dir_ / "zero").string());
  EXPECT_EQ(zero.exit_code, 1);
  EXPECT_THAT(zero.output, HasSubstr("--detect-every must be at least 1"));
}

}  // namespace
