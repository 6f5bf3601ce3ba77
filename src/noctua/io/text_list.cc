#include "noctua/io/text_list.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "noctua/util/error.h"

namespace noctua::io {

std::vector<TextLine> ReadTextLines(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) ThrowFileError(path, "no such file");
  if (std::filesystem::is_directory(path, error)) ThrowFileError(path, "is a folder, not a list");
  std::ifstream in(path);
  if (!in) ThrowFileError(path, "cannot open");
  std::vector<TextLine> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream fields(text);
    TextLine line{number, {}};
    for (std::string field; fields >> field;) line.fields.push_back(field);
    if (line.fields.empty() || line.fields.front().front() == '#') continue;
    lines.push_back(std::move(line));
  }
  if (in.bad()) ThrowFileError(path, "read failed");
  return lines;
}

double ParseNumber(const std::filesystem::path& path, int line, const std::string& field) {
  double value = 0.0;
  const char* end = field.data() + field.size();
  const auto [stop, code] = std::from_chars(field.data(), end, value);
  if (code != std::errc() || stop != end || !std::isfinite(value)) {
    ThrowLineError(path, line, "'" + field + "' is not a number");
  }
  return value;
}

std::vector<double> ParseNumbers(const std::filesystem::path& path, const TextLine& line,
                                 std::size_t count) {
  if (line.fields.size() != count) {
    ThrowLineError(path, line.number,
                   "expected " + std::to_string(count) + " fields, found " +
                       std::to_string(line.fields.size()));
  }
  std::vector<double> values;
  values.reserve(count);
  for (const std::string& field : line.fields)
    values.push_back(ParseNumber(path, line.number, field));
  return values;
}

}  // namespace noctua::io
