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

// Which sources a command reads.
enum class SourceKinds {
  kAll,         // folder, bag or camera, and --replay-rate (slam)
  kRecordings,  // folder or bag only, every frame (extract, eval)
};

// Adds the flags to a subcommand; --dataset, --bag and --live exclude one another. With
// SourceKinds::kRecordings the command has no --live and no --replay-rate.
void AddSourceFlags(CLI::App& command, SourceFlags& flags, SourceKinds kinds = SourceKinds::kAll);

}  // namespace noctua::app
