#pragma once

// Test helper: runs the noctua binary (NOCTUA_BINARY, set by the test target) and captures its
// exit code and output, for the command-line tests.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace noctua::app::testing {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command line.
inline CommandResult RunCommand(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  CommandResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline CommandResult RunNoctua(const std::string& arguments) {
  return RunCommand(std::string(NOCTUA_BINARY) + " " + arguments);
}

}  // namespace noctua::app::testing
