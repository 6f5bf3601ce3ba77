#pragma once

#include <filesystem>

namespace noctua {

// The folder holding data/ and models/ (real frames and detector models, never shipped with the
// library): the environment variable NOCTUA_SHARED_DIR when it is set, otherwise `fallback`
// (each caller knows its own default, e.g. the source tree's ../shared). Throws noctua::Error
// when that folder has no data/: callers that need real data must fail loudly, never skip.
std::filesystem::path FindSharedDir(const std::filesystem::path& fallback);

}  // namespace noctua
