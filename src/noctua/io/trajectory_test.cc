#include "noctua/io/trajectory.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::io {
namespace {

using ::testing::HasSubstr;

class TrajectoryTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_trajectory_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  std::string ErrorOf(const std::filesystem::path& path) {
    try {
      ReadTumTrajectory(path);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
};

TEST_F(TrajectoryTest, ReadsRealGroundTruthFiles) {
  const Trajectory fr1 =
      ReadTumTrajectory(testing::DataDir() / "tum_fr1_rpy_200" / "groundtruth.txt");
  ASSERT_EQ(fr1.size(), 2742u);
  EXPECT_DOUBLE_EQ(fr1.poses().front().timestamp, 1305031225.9334);
  EXPECT_DOUBLE_EQ(fr1.poses().back().timestamp, 1305031253.6027);
  EXPECT_TRUE(
      fr1.poses().front().pose.translation().isApprox(Eigen::Vector3d(1.3357, 0.6698, 1.6180)));

  const Trajectory walking =
      ReadTumTrajectory(testing::DataDir() / "tum_fr3_meta" / "fr3_walking_xyz_groundtruth.txt");
  EXPECT_EQ(walking.size(), 2884u);
  EXPECT_DOUBLE_EQ(walking.poses().front().timestamp, 1341846313.6378);
  EXPECT_DOUBLE_EQ(walking.poses().back().timestamp, 1341846342.4702);
  EXPECT_EQ(
      ReadTumTrajectory(testing::DataDir() / "tum_fr3_meta" / "fr3_sitting_xyz_groundtruth.txt")
          .size(),
      4251u);
}

TEST_F(TrajectoryTest, InterpolatesLinearlyAndBySlerpAndRefusesGapsAndOutside) {
  const auto path = Write("gt.txt",
                          "# timestamp tx ty tz qx qy qz qw\n"
                          "10.0 0 0 0 0 0 0 1\n"
                          "10.1 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n"
                          "20.0 1 2 3 0 0 0 1\n");
  const Trajectory trajectory = ReadTumTrajectory(path);
  const auto pose = trajectory.Interpolate(10.025);
  ASSERT_TRUE(pose.has_value());
  EXPECT_TRUE(pose->translation().isApprox(Eigen::Vector3d(0.25, 0.5, 0.75)));
  EXPECT_NEAR(Eigen::AngleAxisd(pose->rotation()).angle(), 0.25 * M_PI / 2, 1e-9);
  EXPECT_FALSE(trajectory.Interpolate(9.99).has_value());
  EXPECT_FALSE(trajectory.Interpolate(15.0).has_value());  // across a 9.9 s gap
  EXPECT_TRUE(trajectory.Interpolate(15.0, 10.0).has_value());
  EXPECT_TRUE(trajectory.Interpolate(20.0).has_value());
}

TEST_F(TrajectoryTest, WriteThenReadGivesTheSamePoses) {
  const Trajectory original =
      ReadTumTrajectory(testing::DataDir() / "tum_fr1_rpy_200" / "groundtruth.txt");
  const auto path = dir_ / "copy.txt";
  WriteTumTrajectory(path, original);
  const Trajectory copy = ReadTumTrajectory(path);
  ASSERT_EQ(copy.size(), original.size());
  for (std::size_t i = 0; i < copy.size(); i += 97) {
    EXPECT_NEAR(copy.poses()[i].timestamp, original.poses()[i].timestamp, 1e-6);
    EXPECT_TRUE(copy.poses()[i].pose.isApprox(original.poses()[i].pose, 1e-6));
  }
}

TEST_F(TrajectoryTest, BadFilesNameFileAndLine) {
  EXPECT_THAT(ErrorOf(dir_ / "absent.txt"), HasSubstr("absent.txt: no such file"));
  EXPECT_THAT(ErrorOf(Write("empty.txt", "# nothing\n")), HasSubstr("empty.txt: holds no poses"));
  EXPECT_THAT(ErrorOf(Write("short.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n")),
              HasSubstr("short.txt:2: expected 8 fields, found 7"));
  EXPECT_THAT(ErrorOf(Write("word.txt", "1 0 0 0 0 0 0 1\n\n2 0 0 x 0 0 0 1\n")),
              HasSubstr("word.txt:3: 'x' is not a number"));
  EXPECT_THAT(ErrorOf(Write("zero_q.txt", "1 0 0 0 0 0 0 0\n")),
              HasSubstr("zero_q.txt:1: quaternion has zero length"));
  EXPECT_THAT(ErrorOf(Write("order.txt", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n")),
              HasSubstr("order.txt:2: timestamp does not increase"));
}

}  // namespace
}  // namespace noctua::io
