#pragma once

#include <filesystem>
#include <string>

#include "noctua/pipeline/method.h"

namespace noctua::pipeline {

// The method configuration a settings file describes: the extractor options (ORB-SLAM keys and
// the `extractor:` map) and the dynamic stage (`dynamic:` map). An empty `settings` gives the
// defaults; a non-empty `detector_model` replaces the file's model. Checked before it is
// returned; throws noctua::Error naming the file and key for anything invalid.
MethodConfig LoadMethodConfig(const std::filesystem::path& settings,
                              const std::string& detector_model = "");

}  // namespace noctua::pipeline
