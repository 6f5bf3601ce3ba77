#include "noctua/io/output_dir.h"

#include <fstream>

#include "noctua/util/error.h"

namespace noctua::io {

void PrepareOutputDir(const std::filesystem::path& dir, bool force) {
  std::error_code error;
  if (std::filesystem::exists(dir, error)) {
    if (!std::filesystem::is_directory(dir, error))
      ThrowFileError(dir, "exists and is not a folder");
    if (!std::filesystem::is_empty(dir, error) && !force) {
      ThrowFileError(dir, "output folder exists and is not empty (use --force to write into it)");
    }
  } else if (!std::filesystem::create_directories(dir, error)) {
    ThrowFileError(dir, "cannot create the output folder: " + error.message());
  }
  const auto probe = dir / ".noctua_write_probe";
  {
    std::ofstream out(probe);
    if (!out) ThrowFileError(dir, "output folder is not writable");
  }
  std::filesystem::remove(probe, error);
}

void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& text) {
  const auto temporary = std::filesystem::path(path.string() + ".partial");
  {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) ThrowFileError(path, "cannot open for writing");
    out << text;
    if (!out.flush()) ThrowFileError(path, "write failed");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) ThrowFileError(path, "cannot move the finished file into place: " + error.message());
}

}  // namespace noctua::io
