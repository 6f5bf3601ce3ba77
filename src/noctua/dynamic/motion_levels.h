#pragma once

#include <array>
#include <filesystem>
#include <set>
#include <string>

#include "noctua/dynamic/coco.h"

namespace YAML {
class Node;
}

namespace noctua::dynamic {

// How likely objects of a class are to move (the paper's Table 1).
enum class MotionLevel { kStatic = 0, kLow = 1, kMedium = 2, kHigh = 3 };

// Parses "static", "low", "medium", "high"; throws noctua::Error on anything else.
MotionLevel ParseMotionLevel(const std::string& name);
std::string ToString(MotionLevel level);

// Motion level of every COCO class. The default is the paper's Table 1: high = person;
// medium = chair, book; low = dining table (the paper's "desk") and tv; every other class static.
class MotionLevelTable {
 public:
  MotionLevelTable();  // Table 1

  MotionLevel Level(int class_id) const;  // kStatic for ids outside the COCO range
  void Set(int class_id, MotionLevel level);

  // Applies the overrides of a YAML file on top of this table. Format (both keys optional):
  //   motion_levels: {person: high, "cell phone": medium, car: high}
  //   dynamic_levels: [high, medium]
  // The second key, when present, replaces *dynamic_levels. Throws noctua::Error naming the file
  // and line for an unknown class or level, and the file for a missing or malformed file.
  void LoadYaml(const std::filesystem::path& path, std::set<MotionLevel>* dynamic_levels);
  // Same, on an already parsed node (`source` names it in error messages).
  void Apply(const YAML::Node& node, const std::filesystem::path& source,
             std::set<MotionLevel>* dynamic_levels);

 private:
  std::array<MotionLevel, kNumCocoClasses> levels_{};
};

}  // namespace noctua::dynamic
