#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "noctua/util/error.h"

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

// Reads `key` of `node` into `value` as T when present (returns false when absent or null).
// Throws noctua::Error naming `source`, the line and the key when the value has the wrong type.
template <typename T>
bool ReadSetting(const YAML::Node& node, const std::string& key, const std::string& source,
                 T& value) {
  const YAML::Node entry = node[key];
  if (!entry.IsDefined() || entry.IsNull()) return false;
  try {
    value = entry.as<T>();
  } catch (const YAML::Exception&) {
    ThrowLineError(source, entry.Mark().line + 1,
                   "setting '" + key + "' has the wrong type or value");
  }
  return true;
}

}  // namespace noctua::io
