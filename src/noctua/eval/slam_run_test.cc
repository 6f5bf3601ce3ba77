#include "noctua/eval/slam_run.h"

#include <gtest/gtest.h>

#include <limits>

#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

slam::FrameOutcome Outcome(slam::TrackingState state, double track_ms, double mapping_ms) {
  slam::FrameOutcome f;
  f.timestamp = 1.5;
  f.state = state;
  f.method = state == slam::TrackingState::kOk ? "motion" : "";
  f.keypoints = 1000;
  f.inliers = 250;
  f.position_sigma_m =
      state == slam::TrackingState::kOk ? 0.0042 : std::numeric_limits<double>::infinity();
  f.rotation_sigma_deg = 0.125;
  f.residual_px =
      state == slam::TrackingState::kOk ? 0.875 : std::numeric_limits<double>::infinity();
  f.new_keyframe = mapping_ms > 0.0;
  f.keyframes = 3;
  f.map_points = 700;
  f.stage_ms = {{"track", track_ms}};
  if (mapping_ms > 0.0) f.stage_ms["mapping"] = mapping_ms;
  return f;
}

// A frame without a pose has empty sigma cells, and a stage the frame did not have (here the lost
// frame's mapping) an empty cell rather than a time of 0.
TEST(FramesCsvTest, OneRowPerFrameWithEmptySigmaWithoutPose) {
  slam::SequenceRun run;
  run.frames = {Outcome(slam::TrackingState::kOk, 2.0, 10.0),
                Outcome(slam::TrackingState::kLost, 3.0, 0.0)};
  run.frames[1].index = 1;
  const std::string csv = FramesCsv(run, {"track", "mapping"}, {120.0});
  EXPECT_EQ(
      csv,
      "frame,timestamp,state,method,keypoints,inliers,moving_keypoints,position_sigma_mm,"
      "rotation_sigma_deg,residual_px,keyframe,keyframes,map_points,rss_mb,track_ms,mapping_ms\n"
      "0,1.500000,ok,motion,1000,250,0,4.20,0.125,0.875,1,3,700,120.0,2.000,10.000\n"
      "1,1.500000,lost,,1000,250,0,,,,0,3,700,0.0,3.000,\n");
}

// A real-time run: the frames the source dropped get rows of their own, in frame order, so that
// the file lists every frame the source delivered.
TEST(FramesCsvTest, DroppedFramesHaveARowInFrameOrder) {
  slam::SequenceRun run;
  run.frames = {Outcome(slam::TrackingState::kOk, 2.0, 0.0),
                Outcome(slam::TrackingState::kOk, 2.0, 0.0)};
  run.frames[1].index = 3;
  run.dropped_frames = {{1, 1.25}, {2, 1.5}, {4, 2.0}};
  const std::string csv = FramesCsv(run, {"track"}, {});
  EXPECT_EQ(csv,
            "frame,timestamp,state,method,keypoints,inliers,moving_keypoints,position_sigma_mm,"
            "rotation_sigma_deg,residual_px,keyframe,keyframes,map_points,rss_mb,track_ms\n"
            "0,1.500000,ok,motion,1000,250,0,4.20,0.125,0.875,0,3,700,0.0,2.000\n"
            "1,1.250000,dropped,,,,,,,,,,,,\n"
            "2,1.500000,dropped,,,,,,,,,,,,\n"
            "3,1.500000,ok,motion,1000,250,0,4.20,0.125,0.875,0,3,700,0.0,2.000\n"
            "4,2.000000,dropped,,,,,,,,,,,,\n");
}

TEST(SummarizeStagesTest, MedianMeanAndMaxOverTheFramesThatHaveTheStage) {
  std::vector<slam::FrameOutcome> frames = {Outcome(slam::TrackingState::kOk, 1.0, 30.0),
                                            Outcome(slam::TrackingState::kOk, 2.0, 0.0),
                                            Outcome(slam::TrackingState::kOk, 6.0, 0.0)};
  const std::vector<StageTiming> timing = SummarizeStages(frames, {"track", "mapping"});
  ASSERT_EQ(timing.size(), 2u);
  EXPECT_EQ(timing[0].stage, "track");
  EXPECT_DOUBLE_EQ(timing[0].median_ms, 2.0);
  EXPECT_DOUBLE_EQ(timing[0].mean_ms, 3.0);
  EXPECT_DOUBLE_EQ(timing[0].p95_ms, 5.6);  // interpolated between 2 and 6
  EXPECT_DOUBLE_EQ(timing[0].max_ms, 6.0);
  EXPECT_DOUBLE_EQ(timing[1].mean_ms, 30.0);  // only the keyframe has a mapping time
}

TEST(SlamRunOptionsTest, CheckNamesTheField) {
  SlamRunOptions options;
  options.config = "config/tum_fr1.yaml";
  EXPECT_NO_THROW(options.Check());
  options.brightness = 0.0;
  EXPECT_THROW(options.Check(), Error);
  options.brightness = 1.0;
  options.config.clear();
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::eval
