#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace noctua {

// The one exception type noctua throws for bad input or bad settings. Its message is written for
// the user: it names the file (and line, where there is one) and says what is wrong.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws Error("<path>: <problem>").
[[noreturn]] void ThrowFileError(const std::filesystem::path& path, const std::string& problem);

// Throws Error("<path>:<line>: <problem>").
[[noreturn]] void ThrowLineError(const std::filesystem::path& path, int line,
                                 const std::string& problem);

// Throws Error(message) when condition is false; used by the options structs' Check().
void CheckOption(bool condition, const std::string& message);

}  // namespace noctua
