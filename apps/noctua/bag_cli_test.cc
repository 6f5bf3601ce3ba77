// `noctua extract` and `noctua eval` on a ROS1 bag: the same per-frame results as on the folder
// the bag was written from, and a one-line error naming the bag and topic when it lacks one.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "noctua/io/dataset.h"
#include "noctua/io/ros_bag.h"
#include "noctua/testing/shared_data.h"

namespace {

namespace fs = std::filesystem;
using noctua::app::testing::CommandResult;
using noctua::app::testing::RunNoctua;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr int kBagFrames = 40;  // the first frames of tum_fr1_rpy_200, all within ground truth

fs::path Fr1Dir() { return noctua::testing::DataDir() / "tum_fr1_rpy_200"; }
std::string Camera() { return std::string(NOCTUA_SOURCE_DIR) + "/config/tum_fr1.yaml"; }

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

std::vector<std::string> ReadLines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// counts.csv without its timing column (method, frame, timestamp, count).
std::vector<std::string> CountsWithoutTimes(const fs::path& path) {
  std::vector<std::string> lines = ReadLines(path);
  for (std::string& line : lines) line = line.substr(0, line.rfind(','));
  return lines;
}

class BagCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::create_directories(Dir());
    noctua::io::RosBagWriteOptions write;
    write.max_frames = kBagFrames;
    noctua::io::WriteRosBag(noctua::io::Sequence::Open(Fr1Dir()), 5000.0, Bag(), write);
  }
  static void TearDownTestSuite() { fs::remove_all(Dir()); }
  static fs::path Dir() {
    return fs::temp_directory_path() / ("noctua_bag_cli_test_" + std::to_string(::getpid()));
  }
  static fs::path Bag() { return Dir() / "fr1.bag"; }
};

// The bag's colour frames give the overlays and counts of the folder's image files: the overlay
// names are the TUM file names (the times), and every count after every stage is equal.
TEST_F(BagCliTest, ExtractFromABagGivesTheCountsOfTheFolderImages) {
  const int frames = 5;
  const noctua::io::Sequence sequence = noctua::io::Sequence::Open(Fr1Dir());
  std::string images;
  for (int i = 0; i < frames; ++i) images.append(" ").append(sequence.frame(i).rgb_path.string());
  const fs::path from_files = Dir() / "extract_files";
  const fs::path from_bag = Dir() / "extract_bag";
  const fs::path from_folder = Dir() / "extract_folder";
  const std::string method = " --method paper --out ";
  const CommandResult files = RunNoctua("extract" + images + method + from_files.string());
  ASSERT_EQ(files.exit_code, 0) << files.output;
  const CommandResult bag = RunNoctua("extract --bag " + Bag().string() + " --max-frames " +
                                      std::to_string(frames) + method + from_bag.string());
  ASSERT_EQ(bag.exit_code, 0) << bag.output;
  EXPECT_THAT(bag.output, HasSubstr("wrote 5 overlay(s)"));
  const CommandResult folder = RunNoctua("extract --dataset " + Fr1Dir().string() +
                                         " --max-frames 5" + method + from_folder.string());
  ASSERT_EQ(folder.exit_code, 0) << folder.output;

  const nlohmann::json expected = ReadJson(from_files / "summary.json")["images"];
  const nlohmann::json from_bag_json = ReadJson(from_bag / "summary.json");
  EXPECT_EQ(from_bag_json["source"], "bag " + Bag().string());
  for (const nlohmann::json& got :
       {from_bag_json["images"], ReadJson(from_folder / "summary.json")["images"]}) {
    ASSERT_EQ(got.size(), static_cast<std::size_t>(frames));
    for (int i = 0; i < frames; ++i) {
      EXPECT_GT(expected[i]["keypoints"].get<int>(), 500);
      EXPECT_EQ(got[i]["keypoints"], expected[i]["keypoints"]) << i;
      EXPECT_EQ(got[i]["counts"], expected[i]["counts"]) << i;
      EXPECT_EQ(got[i]["overlay"], expected[i]["overlay"]) << i;
      EXPECT_EQ(got[i]["frame"], i);
      EXPECT_NEAR(got[i]["timestamp"].get<double>(), sequence.frame(i).timestamp, 1e-6);
      EXPECT_TRUE(fs::is_regular_file(from_bag / got[i]["overlay"].get<std::string>()));
    }
  }
}

// eval on the bag with its ground truth file: the same counts per frame and the same pairs
// (matches, no depth, correct at every tau) as on the folder, frame for frame.
TEST_F(BagCliTest, EvalOnABagScoresEveryPairAsOnTheFolder) {
  const std::string options =
      " --camera " + Camera() + " --methods orb,paper --gap 5 --max-frames 30 --out ";
  const fs::path on_folder = Dir() / "eval_folder";
  const fs::path on_bag = Dir() / "eval_bag";
  const CommandResult folder =
      RunNoctua("eval --dataset " + Fr1Dir().string() + options + on_folder.string());
  ASSERT_EQ(folder.exit_code, 0) << folder.output;
  const CommandResult bag =
      RunNoctua("eval --bag " + Bag().string() + " --groundtruth " +
                (Fr1Dir() / "groundtruth.txt").string() + options + on_bag.string());
  ASSERT_EQ(bag.exit_code, 0) << bag.output;
  EXPECT_THAT(bag.output, HasSubstr("| paper |"));
  const std::vector<std::string> pairs = ReadLines(on_folder / "pairs.csv");
  ASSERT_EQ(pairs.size(), 1u + 2u * 25u);  // header, 25 pairs of each method
  EXPECT_EQ(ReadLines(on_bag / "pairs.csv"), pairs);
  EXPECT_EQ(CountsWithoutTimes(on_bag / "counts.csv"),
            CountsWithoutTimes(on_folder / "counts.csv"));
  EXPECT_THAT(ReadLines(on_bag / "summary.md")[0], HasSubstr("fr1.bag"));
}

// A bag without the topic: extract and eval exit 1 naming the bag and the topic, before an
// output folder is made; eval without --groundtruth or --camera says which is needed.
TEST_F(BagCliTest, ABagWithoutTheTopicOrGroundTruthIsRefusedNamingBagAndTopic) {
  const fs::path out = Dir() / "never";
  const CommandResult extract = RunNoctua("extract --bag " + Bag().string() +
                                          " --rgb-topic /kinect/rgb --out " + out.string());
  EXPECT_EQ(extract.exit_code, 1);
  EXPECT_THAT(extract.output,
              AllOf(HasSubstr(Bag().string()), HasSubstr("/kinect/rgb"),
                    HasSubstr("/camera/rgb/image_color")));  // the topics the bag has
  const std::string truth = " --groundtruth " + (Fr1Dir() / "groundtruth.txt").string();
  const CommandResult eval =
      RunNoctua("eval --bag " + Bag().string() + truth + " --depth-topic /kinect/depth --camera " +
                Camera() + " --out " + out.string());
  EXPECT_EQ(eval.exit_code, 1);
  EXPECT_THAT(eval.output, AllOf(HasSubstr(Bag().string()), HasSubstr("/kinect/depth")));
  const CommandResult no_truth = RunNoctua("eval --bag " + Bag().string() + " --camera " +
                                           Camera() + " --out " + out.string());
  EXPECT_EQ(no_truth.exit_code, 1);
  EXPECT_THAT(no_truth.output, AllOf(HasSubstr(Bag().string()), HasSubstr("--groundtruth")));
  const CommandResult no_camera =
      RunNoctua("eval --bag " + Bag().string() + truth + " --out " + out.string());
  EXPECT_EQ(no_camera.exit_code, 1);
  EXPECT_THAT(no_camera.output, HasSubstr("--camera"));
  const CommandResult live =
      RunNoctua("eval --live --camera " + Camera() + " --out " + out.string());
  EXPECT_NE(live.exit_code, 0);
  EXPECT_THAT(live.output, HasSubstr("--live"));
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
