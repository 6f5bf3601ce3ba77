#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "noctua/io/frame_source.h"

namespace noctua::app {

// Where the frames come from: a folder (--dataset), a ROS1 bag (--bag, --rgb-topic,
// --depth-topic, --groundtruth) or an OpenNI2 camera (--live [URI]), and --replay-rate.
struct SourceFlags {
  io::FrameSourceOptions options;
  std::string live;  // --live's URI, "" for the first camera

  // The options, with the camera when --live was given (with or without a URI).
  io::FrameSourceOptions Options(const CLI::App& command) const;
};

// Adds the flags to a subcommand; --dataset, --bag and --live exclude one another.
void AddSourceFlags(CLI::App& command, SourceFlags& flags);

}  // namespace noctua::app
