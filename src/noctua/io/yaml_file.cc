#include "noctua/io/yaml_file.h"

#include <fstream>
#include <sstream>

#include "noctua/util/error.h"

namespace noctua::io {

YAML::Node LoadYamlFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) ThrowFileError(path, std::filesystem::exists(path) ? "cannot open" : "no such file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  if (text.rfind("%YAML:", 0) == 0) {
    // Blank the directive instead of erasing it, so yaml-cpp's line numbers stay the file's.
    const auto end = text.find('\n');
    text.replace(0, end == std::string::npos ? text.size() : end, "");
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& exception) {
    ThrowLineError(path, exception.mark.line + 1, "invalid YAML: " + exception.msg);
  }
  if (!root.IsMap()) ThrowFileError(path, "expected a YAML map of settings at the top level");
  return root;
}

double RequiredNumber(const YAML::Node& root, const std::string& key,
                      const std::filesystem::path& path) {
  const YAML::Node node = root[key];
  if (!node) ThrowFileError(path, "missing required setting '" + key + "'");
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    ThrowLineError(path, node.Mark().line + 1, "setting '" + key + "' is not a number");
  }
}

double OptionalNumber(const YAML::Node& root, const std::string& key, double fallback,
                      const std::filesystem::path& path) {
  if (!root[key]) return fallback;
  return RequiredNumber(root, key, path);
}

}  // namespace noctua::io
