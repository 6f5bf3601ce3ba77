// The bad-input suite of the noctua command: refused inputs and output folders give exit code 1
// and a one-line reason naming the file, nothing a user owns is overwritten, and no result file
// is left half-written (also when `noctua slam` is interrupted with Ctrl-C).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "cli_runner.h"
#include "noctua/io/trajectory.h"
#include "noctua/testing/shared_data.h"

namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

using noctua::app::testing::CommandResult;
using noctua::app::testing::RunNoctua;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

fs::path Fr1Dir() { return noctua::testing::DataDir() / "tum_fr1_rpy_200"; }
std::string Config() { return std::string(NOCTUA_SOURCE_DIR) + "/config/tum_fr1.yaml"; }

// No result file is half-written: no temporary ".partial" file is left behind.
void ExpectNoPartialFiles(const fs::path& dir) {
  if (!fs::exists(dir)) return;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    EXPECT_THAT(entry.path().string(), Not(HasSubstr(".partial"))) << entry.path();
  }
}

class BadInputCliTest : public ::testing::Test {
 protected:
  void SetUp() override { fs::create_directories(dir_); }
  void TearDown() override { fs::remove_all(dir_); }

  // The first `count` fr1 frames as a TUM folder whose associations.txt points at the real
  // images; `replace_rgb` (when set) stands in for the colour image of frame `replace_at`.
  fs::path Fr1Subset(const std::string& name, int count, int replace_at = -1,
                     const fs::path& replace_rgb = {}) {
    std::ifstream in(Fr1Dir() / "associations.txt");
    std::string text;
    int n = 0;
    for (std::string line; std::getline(in, line) && n < count;) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string t1, f1, t2, f2;
      fields >> t1 >> f1 >> t2 >> f2;
      const fs::path rgb = n == replace_at ? replace_rgb : Fr1Dir() / f1;
      text += t1 + " " + rgb.string() + " " + t2 + " " + (Fr1Dir() / f2).string() + "\n";
      ++n;
    }
    fs::create_directories(dir_ / name);
    std::ofstream(dir_ / name / "associations.txt") << text;
    return dir_ / name;
  }

  fs::path dir_ =
      fs::temp_directory_path() / ("noctua_bad_input_cli_test_" + std::to_string(::getpid()));
};

TEST_F(BadInputCliTest, ExistingOutputFolderIsNotOverwrittenWithoutForce) {
  const fs::path out = dir_ / "mine";
  fs::create_directories(out);
  std::ofstream(out / "trajectory.txt") << "my own file\n";
  const auto result = RunNoctua("slam --dataset " + Fr1Subset("seq", 3).string() + " --config " +
                                Config() + " --method orb --out " + out.string());
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, AllOf(HasSubstr(out.string()), HasSubstr("--force")));
  EXPECT_EQ(ReadText(out / "trajectory.txt"), "my own file\n");

  const auto extract = RunNoctua("extract " + noctua::testing::Fr1RgbPaths(1)[0].string() +
                                 " --out " + out.string());
  EXPECT_EQ(extract.exit_code, 1) << extract.output;
  EXPECT_EQ(ReadText(out / "trajectory.txt"), "my own file\n");

  // With --force the command writes its results into the folder.
  const auto forced = RunNoctua("slam --dataset " + Fr1Subset("seq", 3).string() + " --config " +
                                Config() + " --method orb --force --out " + out.string());
  EXPECT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_THAT(ReadText(out / "trajectory.txt"), HasSubstr("# timestamp tx ty tz"));
  ExpectNoPartialFiles(out);
}

TEST_F(BadInputCliTest, OutputPathThatIsAFileOrUnderAFile) {
  const fs::path file = dir_ / "file.txt";
  std::ofstream(file) << "keep me\n";
  const std::string image = noctua::testing::Fr1RgbPaths(1)[0].string();
  const auto on_file = RunNoctua("extract " + image + " --force --out " + file.string());
  EXPECT_EQ(on_file.exit_code, 1);
  EXPECT_THAT(on_file.output, AllOf(HasSubstr("file.txt"), HasSubstr("is not a folder")));
  EXPECT_EQ(ReadText(file), "keep me\n");
  const auto under_file = RunNoctua("extract " + image + " --out " + (file / "out").string());
  EXPECT_EQ(under_file.exit_code, 1);
  EXPECT_THAT(under_file.output, HasSubstr("cannot create the output folder"));
}

TEST_F(BadInputCliTest, OutputFolderThatIsNotWritable) {
  // root may write anywhere a mode allows nothing; /proc refuses new files even to root.
  fs::path locked = "/proc";
  if (::geteuid() != 0) {
    locked = dir_ / "locked";
    fs::create_directories(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  }
  const auto result = RunNoctua("extract " + noctua::testing::Fr1RgbPaths(1)[0].string() +
                                " --force --out " + locked.string());
  if (::geteuid() != 0) fs::permissions(locked, fs::perms::owner_all);
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, AllOf(HasSubstr(locked.string()), HasSubstr("not writable")));
}

TEST_F(BadInputCliTest, UnreadableImagesStopExtractionWithoutAHalfWrittenSummary) {
  cv::Mat wide;
  cv::imread(noctua::testing::Fr1RgbPaths(1)[0].string()).convertTo(wide, CV_16U, 257.0);
  const fs::path sixteen = dir_ / "sixteen.png";
  ASSERT_TRUE(cv::imwrite(sixteen.string(), wide));
  const fs::path out = dir_ / "extract";
  const auto result = RunNoctua("extract " + noctua::testing::Fr1RgbPaths(1)[0].string() + " " +
                                sixteen.string() + " --out " + out.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.output, AllOf(HasSubstr("sixteen.png"), HasSubstr("8-bit")));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_FALSE(cv::imread(entry.path().string()).empty()) << entry.path();  // complete files
  }
}

TEST_F(BadInputCliTest, TruncatedFrameMidSequenceStopsSlamWithoutResultFiles) {
  const std::string png = ReadText(noctua::testing::Fr1RgbPaths(3)[2]);
  const fs::path truncated = dir_ / "truncated.png";
  std::ofstream(truncated, std::ios::binary) << png.substr(0, png.size() / 3);
  const fs::path out = dir_ / "slam";
  const auto result = RunNoctua("slam --dataset " + Fr1Subset("seq", 5, 2, truncated).string() +
                                " --config " + Config() + " --method orb --out " + out.string());
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, AllOf(HasSubstr("truncated.png"), HasSubstr("cannot decode")));
  EXPECT_FALSE(fs::exists(out / "trajectory.txt"));
  EXPECT_FALSE(fs::exists(out / "report.json"));
  ExpectNoPartialFiles(out);
}

TEST_F(BadInputCliTest, EmptySequenceAndBadSettingsCreateNoOutputFolder) {
  fs::create_directories(dir_ / "empty");
  std::ofstream(dir_ / "empty" / "associations.txt") << "# no frames\n";
  const fs::path out = dir_ / "never";
  const auto empty = RunNoctua("slam --dataset " + (dir_ / "empty").string() + " --config " +
                               Config() + " --out " + out.string());
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_THAT(empty.output, AllOf(HasSubstr("associations.txt"), HasSubstr("has no frames")));
  std::string settings = ReadText(Config());
  settings.replace(settings.find("DepthMapFactor: 5000.0"), 22, "DepthMapFactor: deep");
  std::ofstream(dir_ / "bad.yaml") << settings;
  const auto bad = RunNoctua("slam --dataset " + Fr1Subset("seq", 2).string() + " --config " +
                             (dir_ / "bad.yaml").string() + " --out " + out.string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_THAT(bad.output, AllOf(HasSubstr("bad.yaml"), HasSubstr("DepthMapFactor")));
  EXPECT_FALSE(fs::exists(out));
}

// A map that cannot be used (missing, not a map, made with another method) is refused before
// anything is written.
TEST_F(BadInputCliTest, UnusableMapIsRefusedBeforeTheOutputFolderIsMade) {
  const std::string run =
      "slam --dataset " + Fr1Subset("seq", 3).string() + " --config " + Config() + " --method ";
  const fs::path out = dir_ / "never";
  const auto missing = RunNoctua(run + "orb --out " + out.string() + " --load-map " +
                                 (dir_ / "none.map").string() + " --localize");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, AllOf(HasSubstr("none.map"), HasSubstr("no such map file")));
  std::ofstream(dir_ / "junk.map") << "not a map at all";
  const auto junk =
      RunNoctua(run + "orb --out " + out.string() + " --load-map " + (dir_ / "junk.map").string());
  EXPECT_EQ(junk.exit_code, 1);
  EXPECT_THAT(junk.output, AllOf(HasSubstr("junk.map"), HasSubstr("not a noctua map")));
  const auto saved = RunNoctua(run + "orb --out " + (dir_ / "mapped").string() + " --save-map " +
                               (dir_ / "orb.map").string());
  ASSERT_EQ(saved.exit_code, 0) << saved.output;
  const auto other = RunNoctua(run + "paper --out " + out.string() + " --load-map " +
                               (dir_ / "orb.map").string() + " --localize");
  EXPECT_EQ(other.exit_code, 1);
  EXPECT_THAT(other.output, AllOf(HasSubstr("orb.map"), HasSubstr("feature method 'orb'")));
  EXPECT_FALSE(fs::exists(out));
}

// No camera on a build machine: --live says so, exits 1 and creates nothing.
TEST_F(BadInputCliTest, LiveWithoutACameraSaysSoAndExitsOne) {
  const fs::path out = dir_ / "live_out";
  const auto result = RunNoctua("slam --live --config " + Config() + " --out " + out.string());
  if (result.exit_code == 0) GTEST_SKIP() << "an OpenNI2 camera is connected";
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.output, HasSubstr("no OpenNI2 camera found"));
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInputCliTest, ABagThatIsNotThereOrTruncatedIsNamed) {
  const fs::path out = dir_ / "bag_out";
  const auto missing = RunNoctua("slam --bag " + (dir_ / "none.bag").string() + " --config " +
                                 Config() + " --out " + out.string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("none.bag: no such bag file"));
  std::ofstream(dir_ / "half.bag") << "#ROSBAG V2.0\n";
  const auto truncated = RunNoctua("slam --bag " + (dir_ / "half.bag").string() + " --config " +
                                   Config() + " --out " + out.string());
  EXPECT_EQ(truncated.exit_code, 1);
  EXPECT_THAT(truncated.output, AllOf(HasSubstr("half.bag"), HasSubstr("truncated")));
  const auto both = RunNoctua("slam --bag x.bag --dataset " + Fr1Dir().string() + " --config " +
                              Config() + " --out " + out.string());
  EXPECT_NE(both.exit_code, 0);
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(BadInputCliTest, OneFrameSequenceRunsToTheEnd) {
  const fs::path out = dir_ / "one_out";
  const auto result = RunNoctua("slam --dataset " + Fr1Subset("one", 1).string() + " --config " +
                                Config() + " --method orb --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream in(out / "report.json");
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["frames"], 1);
  EXPECT_LE(report["tracked_frames"].get<int>(), 1);
  EXPECT_FALSE(report.contains("ate"));  // three poses at least are needed for an alignment
}

// Ctrl-C: the process stops at the next frame, writes the trajectory tracked so far completely,
// says so, and exits with 1.
TEST_F(BadInputCliTest, SigintDuringSlamLeavesTheTrajectorySoFarIntact) {
  const fs::path out = dir_ / "interrupted";
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const std::string dataset = Fr1Dir().string();
  const std::string config = Config();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::close(pipe_fds[0]);
    ::execl(NOCTUA_BINARY, NOCTUA_BINARY, "slam", "--dataset", dataset.c_str(), "--config",
            config.c_str(), "--method", "orb", "--progress-every", "1", "--out",
            out.string().c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  FILE* output = ::fdopen(pipe_fds[0], "r");
  ASSERT_NE(output, nullptr);
  std::string text;
  std::array<char, 4096> line{};
  bool signalled = false;
  while (std::fgets(line.data(), line.size(), output) != nullptr) {
    text += line.data();
    // Interrupt once the run is well under way (frame 30 of 200).
    if (!signalled && text.find(" 30/200 ") != std::string::npos) {
      ASSERT_EQ(::kill(pid, SIGINT), 0);
      signalled = true;
    }
  }
  std::fclose(output);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(signalled) << text;
  ASSERT_TRUE(WIFEXITED(status)) << text;
  EXPECT_EQ(WEXITSTATUS(status), 1) << text;
  EXPECT_THAT(text, AllOf(HasSubstr("interrupted"), HasSubstr("trajectory.txt"),
                          HasSubstr("tracked so far")));
  const noctua::io::Trajectory trajectory = noctua::io::ReadTumTrajectory(out / "trajectory.txt");
  EXPECT_GE(trajectory.size(), 10u);
  EXPECT_LT(trajectory.size(), 200u);
  std::ifstream in(out / "report.json");
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["interrupted"], true);
  EXPECT_EQ(report["tracked_frames"].get<std::size_t>(), trajectory.size());
  ExpectNoPartialFiles(out);
}

}  // namespace
