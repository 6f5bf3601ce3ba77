#include "noctua/util/error.h"

namespace noctua {

void ThrowFileError(const std::filesystem::path& path, const std::string& problem) {
  throw Error(path.string() + ": " + problem);
}

void ThrowLineError(const std::filesystem::path& path, int line, const std::string& problem) {
  throw Error(path.string() + ":" + std::to_string(line) + ": " + problem);
}

void CheckOption(bool condition, const std::string& message) {
  if (!condition) throw Error("invalid option: " + message);
}

}  // namespace noctua
