#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace noctua::io {

// One meaningful line of a TUM-style text list, split on white space.
struct TextLine {
  int number = 0;  // 1-based line number in the file
  std::vector<std::string> fields;
};

// The non-blank, non-comment ('#') lines of a text file. Throws noctua::Error naming the file
// when it is missing or cannot be read.
std::vector<TextLine> ReadTextLines(const std::filesystem::path& path);

// Parses exactly `count` finite numbers from a line; throws noctua::Error naming file and line
// otherwise.
std::vector<double> ParseNumbers(const std::filesystem::path& path, const TextLine& line,
                                 std::size_t count);

// Parses a finite number (a timestamp) from one field; throws naming file and line otherwise.
double ParseNumber(const std::filesystem::path& path, int line, const std::string& field);

}  // namespace noctua::io
