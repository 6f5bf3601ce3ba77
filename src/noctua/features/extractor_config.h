#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "noctua/features/extractor_options.h"

namespace noctua::features {

// Reads extractor options from settings: ORB-SLAM2/3 keys (ORBextractor.nFeatures, .scaleFactor,
// .nLevels, .iniThFAST, .minThFAST) at the top level, and noctua's own keys in an `extractor:`
// map (see config/*.yaml). Keys that are absent keep the value of `defaults`; unknown keys in
// `extractor:` are warned about; wrong types throw noctua::Error naming `source` and the key.
ExtractorOptions ExtractorOptionsFromYaml(const YAML::Node& root, const std::string& source,
                                          ExtractorOptions defaults = {});

// The same from a file (ORB-SLAM's "%YAML:1.0" header accepted).
ExtractorOptions LoadExtractorOptions(const std::filesystem::path& path,
                                      ExtractorOptions defaults = {});

}  // namespace noctua::features
