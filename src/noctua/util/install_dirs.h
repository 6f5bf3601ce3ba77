#pragma once

#include <filesystem>
#include <vector>

namespace noctua {

// The folder of the running program (from /proc/self/exe); empty when it cannot be told.
std::filesystem::path ExecutableDir();

// The folder of the camera presets (config/*.yaml, installed as share/noctua/config): the
// environment variable NOCTUA_CONFIG_DIR when it is set, else the first of `candidates` that is
// a folder. Callers pass their own places, most specific first: the installed command
// <bin>/../share/noctua/config, the Python package its prefix's, a build the source tree's
// config/. Throws noctua::Error listing every place looked at when none exists.
std::filesystem::path FindConfigDir(const std::vector<std::filesystem::path>& candidates);

}  // namespace noctua
