// The flags that say where a command's frames come from.
#include "source_flags.h"

namespace noctua::app {

void AddSourceFlags(CLI::App& command, SourceFlags& flags, SourceKinds kinds) {
  io::FrameSourceOptions& source = flags.options;
  auto* dataset = command.add_option("-d,--dataset", source.dataset,
                                     "Sequence folder (TUM RGB-D or OpenLORIS)");
  auto* bag = command.add_option(
      "--bag", source.bag, "ROS1 bag of sensor_msgs/Image colour and depth (docs/datasets.md)");
  dataset->excludes(bag);
  command.add_option("--rgb-topic", source.rgb_topic, "The bag's colour topic (rgb8, bgr8)")
      ->capture_default_str()
      ->needs(bag);
  command
      .add_option("--depth-topic", source.depth_topic,
                  "The bag's depth topic (32FC1 metres, 16UC1 millimetres)")
      ->capture_default_str()
      ->needs(bag);
  command
      .add_option("--groundtruth", source.ground_truth,
                  "TUM-format ground truth of the bag (slam: ATE/RPE; eval: judging matches)")
      ->needs(bag);
  if (kinds == SourceKinds::kRecordings) return;
  auto* live = command
                   .add_option("--live", flags.live,
                               "OpenNI2 camera (Kinect, Xtion) at its rate, frames dropped "
                               "while the SLAM is busy; optional device URI")
                   ->expected(0, 1);
  dataset->excludes(live);
  bag->excludes(live);
  command
      .add_option("--replay-rate", source.replay_rate,
                  "Play the folder or bag at this multiple of its recording's rate, dropping "
                  "frames that arrive while the SLAM is busy, as a camera does (0: every frame)")
      ->excludes(live);
  command
      .add_flag("--replay-preload", source.replay_preload,
                "With --replay-rate: decode the whole recording into memory first (about 2 MB "
                "per 640x480 frame), so that, as with a camera, no decoding competes with the "
                "SLAM while it plays")
      ->excludes(live);
}

io::FrameSourceOptions SourceFlags::Options(const CLI::App& command) const {
  io::FrameSourceOptions source = options;
  const CLI::Option* live_flag = command.get_option_no_throw("--live");
  if (live_flag != nullptr && live_flag->count() > 0) source.live = live;
  return source;
}

}  // namespace noctua::app
