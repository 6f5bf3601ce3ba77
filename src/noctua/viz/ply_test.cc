#include "noctua/viz/ply.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "noctua/util/error.h"
#include "noctua/viz/viz_test_support.h"

namespace noctua::viz {
namespace {

TEST(PlyTest, HeaderCountsThePointsAndTheKeyFramesThatFollowIt) {
  MapCloud cloud;
  cloud.points = {{1.0, 2.0, 3.0}, {-0.5, 0.25, 4.0}};
  cloud.colours.push_back(cv::Vec3b(10, 20, 30));  // BGR
  cloud.colours.push_back(MapPointColours::kGrey);
  cloud.keyframes = {{0.0, 0.0, 0.0}};
  EXPECT_EQ(FormatPly(cloud),
            "ply\nformat ascii 1.0\ncomment noctua SLAM map\n"
            "comment vertices 0..2 (exclusive): 2 map points\n"
            "comment then 1 keyframe camera centres (magenta)\n"
            "element vertex 3\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
            "1.00000 2.00000 3.00000 30 20 10\n"
            "-0.50000 0.25000 4.00000 160 160 160\n"
            "0.00000 0.00000 0.00000 255 0 255\n");
}

TEST(PlyTest, WritingIntoAMissingFolderNamesTheFile) {
  try {
    WritePly(MapCloud(), "/nonexistent-folder/map.ply");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("map.ply"), std::string::npos) << error.what();
  }
}

// 30 real frames: every good point of the final map is in the snapshot, most of them coloured
// from the keyframe that made them (not the grey of points never sampled).
TEST(PlyTest, SnapshotOfARealMapHasEveryPointAndKeyFrameMostlyInColour) {
  MapPointColours colours;
  MapCloud cloud;
  int map_points = 0, keyframes = 0;
  testing::RunFr1(30, [&](const slam::FrameView& view) {
    colours.Update(view);
    cloud = SnapshotMap(*view.map, colours);
    map_points = view.map->NumMapPoints();
    keyframes = view.map->NumKeyFrames();
  });
  ASSERT_GT(map_points, 500);
  EXPECT_EQ(cloud.points.size(), static_cast<std::size_t>(map_points));
  EXPECT_EQ(cloud.colours.size(), cloud.points.size());
  EXPECT_EQ(cloud.keyframes.size(), static_cast<std::size_t>(keyframes));
  const auto grey = std::count(cloud.colours.begin(), cloud.colours.end(), MapPointColours::kGrey);
  EXPECT_LT(grey, map_points / 10);
}

}  // namespace
}  // namespace noctua::viz
