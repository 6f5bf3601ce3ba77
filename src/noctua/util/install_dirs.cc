#include "noctua/util/install_dirs.h"

#include <cstdlib>
#include <string>

#include "noctua/util/error.h"

namespace noctua {

std::filesystem::path ExecutableDir() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path() : exe.parent_path();
}

std::filesystem::path FindConfigDir(const std::vector<std::filesystem::path>& candidates) {
  if (const char* env = std::getenv("NOCTUA_CONFIG_DIR"); env != nullptr && *env != '\0') {
    if (!std::filesystem::is_directory(env)) {
      ThrowFileError(env, "NOCTUA_CONFIG_DIR is not a folder");
    }
    return env;
  }
  std::string looked;
  for (const auto& candidate : candidates) {
    std::error_code error;
    if (!candidate.empty() && std::filesystem::is_directory(candidate, error)) {
      return std::filesystem::weakly_canonical(candidate);
    }
    looked += (looked.empty() ? "" : ", ") + candidate.string();
  }
  throw Error("no camera presets folder (looked at " + looked +
              "); set NOCTUA_CONFIG_DIR or pass the settings file");
}

}  // namespace noctua
