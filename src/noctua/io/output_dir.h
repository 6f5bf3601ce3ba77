#pragma once

#include <filesystem>
#include <string>

namespace noctua::io {

// Makes `dir` ready to receive a command's outputs. An existing, non-empty folder is refused
// unless `force` is set, so that nothing a user owns is overwritten by accident. Throws
// noctua::Error naming the folder when it cannot be created or written.
void PrepareOutputDir(const std::filesystem::path& dir, bool force);

// Writes text to a file atomically (temporary file + rename), so a failure never leaves a
// half-written result behind. Throws noctua::Error naming the file on failure.
void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& text);

}  // namespace noctua::io
