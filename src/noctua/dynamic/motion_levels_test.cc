#include "noctua/dynamic/motion_levels.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

std::filesystem::path WriteFile(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(path) << text;
  return path;
}

TEST(MotionLevelTable, DefaultsArePaperTable1) {
  const MotionLevelTable table;
  EXPECT_EQ(table.Level(CocoClassId("person")), MotionLevel::kHigh);
  EXPECT_EQ(table.Level(CocoClassId("chair")), MotionLevel::kMedium);
  EXPECT_EQ(table.Level(CocoClassId("book")), MotionLevel::kMedium);
  EXPECT_EQ(table.Level(CocoClassId("dining table")), MotionLevel::kLow);
  EXPECT_EQ(table.Level(CocoClassId("tv")), MotionLevel::kLow);
  int non_static = 0;
  for (int id = 0; id < kNumCocoClasses; ++id)
    non_static += table.Level(id) != MotionLevel::kStatic;
  EXPECT_EQ(non_static, 5);
  EXPECT_EQ(table.Level(-1), MotionLevel::kStatic);
  EXPECT_EQ(table.Level(80), MotionLevel::kStatic);
  EXPECT_EQ(CocoClassName(0), "person");
  EXPECT_EQ(CocoClassName(79), "toothbrush");
  EXPECT_EQ(CocoClassId("giraffe"), 23);
  EXPECT_EQ(CocoClassId("desk"), -1);
}

TEST(MotionLevelTable, YamlOverridesOnTopOfTheDefaults) {
  const auto path = WriteFile("levels.yaml",
                              "motion_levels:\n"
                              "  chair: static\n"
                              "  dog: high\n"
                              "  \"cell phone\": medium\n"
                              "dynamic_levels: [high, medium]\n");
  MotionLevelTable table;
  std::set<MotionLevel> dynamic = {MotionLevel::kHigh};
  table.LoadYaml(path, &dynamic);
  EXPECT_EQ(table.Level(CocoClassId("chair")), MotionLevel::kStatic);
  EXPECT_EQ(table.Level(CocoClassId("dog")), MotionLevel::kHigh);
  EXPECT_EQ(table.Level(CocoClassId("cell phone")), MotionLevel::kMedium);
  EXPECT_EQ(table.Level(CocoClassId("person")), MotionLevel::kHigh);  // untouched default
  EXPECT_EQ(dynamic, (std::set<MotionLevel>{MotionLevel::kHigh, MotionLevel::kMedium}));
}

TEST(MotionLevelTable, ErrorsNameTheFileAndLine) {
  MotionLevelTable table;
  std::set<MotionLevel> dynamic;
  const auto unknown_class =
      WriteFile("bad_class.yaml", "motion_levels:\n  person: high\n  desk: low\n");
  try {
    table.LoadYaml(unknown_class, &dynamic);
    FAIL() << "an unknown class was accepted";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("bad_class.yaml:3"));
    EXPECT_THAT(error.what(), ::testing::HasSubstr("'desk' is not a COCO class"));
  }
  const auto unknown_level = WriteFile("bad_level.yaml", "motion_levels:\n  person: fast\n");
  try {
    table.LoadYaml(unknown_level, &dynamic);
    FAIL() << "an unknown level was accepted";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("bad_level.yaml:2"));
    EXPECT_THAT(error.what(), ::testing::HasSubstr("unknown motion level 'fast'"));
  }
  const auto bad_list = WriteFile("bad_list.yaml", "dynamic_levels: high\n");
  EXPECT_THROW(table.LoadYaml(bad_list, &dynamic), Error);
  const auto broken = WriteFile("broken.yaml", "motion_levels: [unclosed\n");
  EXPECT_THROW(table.LoadYaml(broken, &dynamic), Error);
  EXPECT_THROW(table.LoadYaml("/nonexistent/levels.yaml", &dynamic), Error);
  EXPECT_THROW(ParseMotionLevel("High"), Error);
}

}  // namespace
}  // namespace noctua::dynamic
