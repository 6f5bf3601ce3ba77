#include "noctua/dynamic/motion_levels.h"

#include <yaml-cpp/yaml.h>

#include "noctua/util/error.h"

namespace noctua::dynamic {

MotionLevel ParseMotionLevel(const std::string& name) {
  if (name == "static") return MotionLevel::kStatic;
  if (name == "low") return MotionLevel::kLow;
  if (name == "medium") return MotionLevel::kMedium;
  if (name == "high") return MotionLevel::kHigh;
  throw Error("unknown motion level '" + name + "' (expected static, low, medium or high)");
}

std::string ToString(MotionLevel level) {
  switch (level) {
    case MotionLevel::kStatic:
      return "static";
    case MotionLevel::kLow:
      return "low";
    case MotionLevel::kMedium:
      return "medium";
    case MotionLevel::kHigh:
      return "high";
  }
  return "static";
}

MotionLevelTable::MotionLevelTable() {
  levels_.fill(MotionLevel::kStatic);
  Set(CocoClassId("person"), MotionLevel::kHigh);
  Set(CocoClassId("chair"), MotionLevel::kMedium);
  Set(CocoClassId("book"), MotionLevel::kMedium);
  Set(CocoClassId("dining table"), MotionLevel::kLow);
  Set(CocoClassId("tv"), MotionLevel::kLow);
}

MotionLevel MotionLevelTable::Level(int class_id) const {
  if (class_id < 0 || class_id >= kNumCocoClasses) return MotionLevel::kStatic;
  return levels_[static_cast<size_t>(class_id)];
}

void MotionLevelTable::Set(int class_id, MotionLevel level) {
  if (class_id < 0 || class_id >= kNumCocoClasses) {
    throw Error("motion level for class id " + std::to_string(class_id) +
                ", outside the 80 COCO classes");
  }
  levels_[static_cast<size_t>(class_id)] = level;
}

void MotionLevelTable::LoadYaml(const std::filesystem::path& path,
                                std::set<MotionLevel>* dynamic_levels) {
  if (!std::filesystem::exists(path)) ThrowFileError(path, "motion-level file not found");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::Exception& error) {
    ThrowLineError(path, error.mark.line + 1, "not valid YAML: " + error.msg);
  }
  Apply(root, path, dynamic_levels);
}

void MotionLevelTable::Apply(const YAML::Node& node, const std::filesystem::path& source,
                             std::set<MotionLevel>* dynamic_levels) {
  if (!node || node.IsNull()) return;
  if (!node.IsMap()) ThrowLineError(source, node.Mark().line + 1, "expected a mapping");
  const auto level_of = [&](const YAML::Node& value) {
    if (!value.IsScalar()) {
      ThrowLineError(source, value.Mark().line + 1, "expected a motion level");
    }
    try {
      return ParseMotionLevel(value.as<std::string>());
    } catch (const Error& error) {
      ThrowLineError(source, value.Mark().line + 1, error.what());
    }
  };
  if (const YAML::Node levels = node["motion_levels"]) {
    if (!levels.IsMap()) {
      ThrowLineError(source, levels.Mark().line + 1,
                     "motion_levels must map COCO class names to levels");
    }
    for (const auto& entry : levels) {
      const std::string name = entry.first.as<std::string>();
      const int id = CocoClassId(name);
      if (id < 0) {
        ThrowLineError(
            source, entry.first.Mark().line + 1,
            "'" + name + "' is not a COCO class name (e.g. person, chair, dining table)");
      }
      Set(id, level_of(entry.second));
    }
  }
  if (const YAML::Node dynamic = node["dynamic_levels"]) {
    if (!dynamic.IsSequence()) {
      ThrowLineError(source, dynamic.Mark().line + 1,
                     "dynamic_levels must be a list such as [high, medium]");
    }
    std::set<MotionLevel> chosen;
    for (const auto& value : dynamic) chosen.insert(level_of(value));
    if (dynamic_levels != nullptr) *dynamic_levels = chosen;
  }
}

}  // namespace noctua::dynamic
