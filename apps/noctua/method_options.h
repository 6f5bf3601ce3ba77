#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "noctua/pipeline/method.h"

namespace noctua::app {

// The options every command that runs a feature method shares.
struct MethodFlags {
  std::string method = "paper";
  std::string config;          // settings file (ORB-SLAM keys and noctua's sections)
  std::string detector_model;  // ONNX detector for the paper's dynamic regions
};

// Adds --method, --config and --detector to a subcommand.
void AddMethodFlags(CLI::App& command, MethodFlags& flags);

// The method configuration the flags describe (settings file read and checked).
pipeline::MethodConfig MethodConfigFromFlags(const MethodFlags& flags);

}  // namespace noctua::app
