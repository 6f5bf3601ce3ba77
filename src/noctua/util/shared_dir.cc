#include "noctua/util/shared_dir.h"

#include <cstdlib>

#include "noctua/util/error.h"

namespace noctua {

std::filesystem::path FindSharedDir(const std::filesystem::path& fallback) {
  const char* from_environment = std::getenv("NOCTUA_SHARED_DIR");
  const std::filesystem::path dir =
      from_environment && *from_environment ? std::filesystem::path(from_environment) : fallback;
  if (!std::filesystem::is_directory(dir / "data")) {
    ThrowFileError(dir, "the shared data folder is missing (set NOCTUA_SHARED_DIR)");
  }
  return dir;
}

}  // namespace noctua
