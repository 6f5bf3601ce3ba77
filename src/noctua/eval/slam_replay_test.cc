// The SLAM run fed in real time: a folder or bag played at a multiple of its recording's rate,
// frames that arrive while the SLAM is busy dropped (io::RealTimeSource), on real frames.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <set>

#include "noctua/eval/slam_run.h"
#include "noctua/io/realtime_source.h"
#include "noctua/io/ros_bag.h"
#include "noctua/pipeline/method.h"
#include "noctua/pipeline/method_config.h"
#include "noctua/slam/slam_options.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr int kFrames = 24;

SlamRunOptions ReplayOptions(double rate) {
  SlamRunOptions options;
  options.source.dataset = testing::DataDir() / "tum_fr1_rpy_200";
  options.source.replay_rate = rate;
  options.config = "config/tum_fr1.yaml";
  options.method = "orb";
  options.max_frames = kFrames;
  return options;
}

// Every frame the source delivered is either tracked or dropped, never both, and the report and
// frames.csv count them the same way.
void ExpectConsistent(const SlamRunReport& report) {
  const slam::SequenceRun& run = report.run;
  EXPECT_EQ(run.frames.size() + run.dropped_frames.size(), static_cast<std::size_t>(kFrames));
  std::set<int> indices;
  for (const slam::FrameOutcome& frame : run.frames) indices.insert(frame.index);
  for (const io::DroppedFrame& frame : run.dropped_frames) indices.insert(frame.index);
  EXPECT_EQ(indices.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(*indices.rbegin(), kFrames - 1);
  EXPECT_EQ(report.json["dropped_frames"].get<std::size_t>(), run.dropped_frames.size());
  EXPECT_EQ(report.json["frames"].get<std::size_t>() + report.json["dropped_frames"].get<int>(),
            static_cast<std::size_t>(kFrames));
  const std::string csv = FramesCsv(run, SlamReportStages(), report.rss_mb);
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), kFrames + 1U);
}

// 50 times the recording's rate offers the 24 frames within 16 ms, far faster than the SLAM
// takes them: most are dropped (even the first, when the SLAM's threads are not yet taking),
// yet the last is always tracked (nothing replaces it).
TEST(SlamReplayTest, FarTooFastDropsFramesAndCountsEveryOne) {
  const slam::SlamSetup setup = slam::LoadSlamSetup("config/tum_fr1.yaml");
  // Preloaded, so that the replay offers frames as fast as its rate says rather than as fast as
  // PNGs decode.
  io::RealTimeSource replay(
      std::make_unique<io::PreloadedSource>(std::make_unique<io::FolderSource>(
          io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200"), setup.camera.depth_factor,
          kFrames)),
      50.0);
  const auto method = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  SlamRunReport report;
  report.run = slam::RunFrames(replay, setup.camera.Camera(), method->feature2d(), setup.options);
  const slam::SequenceRun& run = report.run;
  EXPECT_GT(run.dropped_frames.size(), 0U);
  ASSERT_FALSE(run.frames.empty());
  EXPECT_EQ(run.frames.back().index, kFrames - 1);
  EXPECT_EQ(run.frames.size() + run.dropped_frames.size(), static_cast<std::size_t>(kFrames));
  const std::string csv = FramesCsv(run, SlamReportStages(), {});
  EXPECT_EQ(static_cast<std::size_t>(std::count(csv.begin(), csv.end(), '\n')), kFrames + 1U);
  std::size_t dropped_rows = 0;
  for (std::size_t at = csv.find(",dropped,"); at != std::string::npos;
       at = csv.find(",dropped,", at + 1)) {
    ++dropped_rows;
  }
  EXPECT_EQ(dropped_rows, run.dropped_frames.size());
}

// Through the whole run and its report: every frame tracked or dropped, counted alike in
// report.json and frames.csv, at a rate that may or may not drop some.
TEST(SlamReplayTest, TheReportCountsEveryFrameAsTrackedOrDropped) {
  const SlamRunReport report = RunSlam(ReplayOptions(50.0));
  ExpectConsistent(report);
  EXPECT_DOUBLE_EQ(report.json["replay_rate"].get<double>(), 50.0);
}

// A twentieth of the recording's rate (1.5 frames/s, slow enough for a sanitizer build) leaves
// the SLAM idle between frames: none dropped,
// and the run is the one made without real time.
TEST(SlamReplayTest, SlowEnoughDropsNoneAndTracksLikeTheUntimedRun) {
  const SlamRunReport replayed = RunSlam(ReplayOptions(0.05));
  ExpectConsistent(replayed);
  EXPECT_TRUE(replayed.run.dropped_frames.empty());
  const SlamRunReport untimed = RunSlam(ReplayOptions(0.0));
  ASSERT_EQ(replayed.run.trajectory.size(), untimed.run.trajectory.size());
  EXPECT_EQ(replayed.run.lost_frames, untimed.run.lost_frames);
  // A replayed frame's latency, from its arrival to its pose, covers its loading, extraction and
  // tracking; a recording read as fast as it goes has none, in the frames and in the report.
  for (const slam::FrameOutcome& frame : replayed.run.frames) {
    ASSERT_EQ(frame.stage_ms.count("latency"), 1u) << "frame " << frame.index;
    EXPECT_GE(frame.stage_ms.at("latency"),
              frame.stage_ms.at("extract") + frame.stage_ms.at("track"))
        << "frame " << frame.index;
  }
  EXPECT_GT(replayed.json["timing_ms"]["latency"]["max"].get<double>(), 0.0);
  for (const slam::FrameOutcome& frame : untimed.run.frames) {
    EXPECT_EQ(frame.stage_ms.count("latency"), 0u);
  }
  EXPECT_FALSE(untimed.json["timing_ms"].contains("latency"));
  const std::string csv = FramesCsv(untimed.run, SlamReportStages(), untimed.rss_mb);
  EXPECT_NE(csv.find(",total_ms,latency_ms\n"), std::string::npos);
}

// In real time nothing can be detected ahead of its frame: a replayed frame takes the newest
// detection finished instead of waiting for its own; read as fast as it goes, every 3rd frame is
// detected ahead and every frame waits for its mask.
TEST(SlamReplayTest, AReplayedFrameNeverWaitsForTheDetector) {
  SlamRunOptions options = ReplayOptions(1.0);
  options.detector_model = (testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx").string();
  const SlamRunReport replayed = RunSlam(options);
  ExpectConsistent(replayed);
  const nlohmann::json& live = replayed.json["detection"];
  EXPECT_THAT(live["mode"].get<std::string>(), HasSubstr("never wait"));
  EXPECT_GE(live["frames_detected"].get<int>(), 1);
  EXPECT_LE(live["frames_detected"].get<int>(), (kFrames + 2) / 3);
  options.source.replay_rate = 0.0;
  const SlamRunReport untimed = RunSlam(options);
  const nlohmann::json& ahead = untimed.json["detection"];
  EXPECT_THAT(ahead["mode"].get<std::string>(), HasSubstr("submitted ahead"));
  EXPECT_EQ(ahead["frames_detected"].get<int>(), (kFrames + 2) / 3);
}

// Frames on demand, as a camera whose frames never run out would hand them, counting how many
// were taken.
class CountingCamera : public io::FrameSource {
 public:
  explicit CountingCamera(std::unique_ptr<io::FrameSource> frames) : frames_(std::move(frames)) {}
  std::string Describe() const override { return "counting camera"; }
  std::optional<std::size_t> size() const override { return frames_->size(); }
  std::optional<io::SourceFrame> Next() override {
    std::optional<io::SourceFrame> frame = frames_->Next();
    if (frame) ++taken_;
    return frame;
  }
  bool real_time() const override { return true; }
  int taken() const { return taken_; }

 private:
  std::unique_ptr<io::FrameSource> frames_;
  std::atomic<int> taken_{0};
};

// A frame taken from a real-time source goes stale while it waits: the run holds one loaded and
// one extracted frame at most beyond the one it tracks, whatever the queues a recording gets.
TEST(SlamReplayTest, ARealTimeSourceIsReadAtMostTwoFramesAhead) {
  const slam::SlamSetup setup = slam::LoadSlamSetup("config/tum_fr1.yaml");
  CountingCamera camera(std::make_unique<io::PreloadedSource>(
      std::make_unique<io::FolderSource>(io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200"),
                                         setup.camera.depth_factor, kFrames)));
  slam::RunOptions run_options;
  ASSERT_GT(run_options.extraction_queue, 1);
  int most_ahead = 0;
  run_options.observe = [&](const slam::FrameView& view) {
    most_ahead = std::max(most_ahead, camera.taken() - (view.index + 1));
  };
  const auto method = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  const slam::SequenceRun run = slam::RunFrames(camera, setup.camera.Camera(), method->feature2d(),
                                                setup.options, run_options);
  EXPECT_EQ(run.frames.size(), static_cast<std::size_t>(kFrames));
  EXPECT_LE(most_ahead, 2);
}

TEST(SlamReplayTest, ABagPlaysInRealTimeToo) {
  const fs::path bag =
      fs::temp_directory_path() / ("noctua_slam_replay_" + std::to_string(::getpid()) + ".bag");
  io::RosBagWriteOptions write;
  write.max_frames = kFrames;
  io::WriteRosBag(io::Sequence::Open(testing::DataDir() / "tum_fr1_rpy_200"), 5000.0, bag, write);
  SlamRunOptions options = ReplayOptions(50.0);
  options.source.dataset.clear();
  options.source.bag = bag;
  const SlamRunReport report = RunSlam(options);
  fs::remove(bag);
  ExpectConsistent(report);
  EXPECT_THAT(report.json["source"].get<std::string>(), HasSubstr("played at 50x"));
}

TEST(SlamReplayTest, ACameraThatIsNotThereIsAnErrorBeforeAnythingRuns) {
  SlamRunOptions options = ReplayOptions(0.0);
  options.source.dataset.clear();
  options.source.live = "";
  try {
    SlamRunner runner(options);
    GTEST_SKIP() << "an OpenNI2 camera is connected";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("no OpenNI2 camera found"));
  }
  options = ReplayOptions(0.0);
  options.source.bag = "x.bag";
  EXPECT_THROW(SlamRunner runner(options), Error);  // a folder and a bag at once
}

}  // namespace
}  // namespace noctua::eval
