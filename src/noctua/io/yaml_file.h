#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

namespace noctua::io {

// Loads a YAML file. ORB-SLAM2/3 settings files begin with OpenCV's "%YAML:1.0" directive, which
// yaml-cpp rejects as malformed; that first line is dropped (line numbers in errors still refer
// to the file as written). Throws noctua::Error naming the file (and line) when it is missing or
// not valid YAML, or when its top level is not a map.
YAML::Node LoadYamlFile(const std::filesystem::path& path);

// Reads a required number under `key` of a top-level map. Throws noctua::Error naming the file,
// the key, and the line when it is missing or not a number.
double RequiredNumber(const YAML::Node& root, const std::string& key,
                      const std::filesystem::path& path);

// Same for an optional key: `fallback` when absent, an error when present but not a number.
double OptionalNumber(const YAML::Node& root, const std::string& key, double fallback,
                      const std::filesystem::path& path);

}  // namespace noctua::io
