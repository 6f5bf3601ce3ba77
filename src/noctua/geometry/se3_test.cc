#include "noctua/geometry/se3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

TEST(Se3Test, InterpolationIsLinearInPositionAndSlerpInRotation) {
  const Pose a = MakePose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  const Pose b = MakePose(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())),
                          Eigen::Vector3d(2, -4, 6));
  const Pose mid = Interpolate(a, b, 0.25);
  EXPECT_TRUE(mid.translation().isApprox(Eigen::Vector3d(0.5, -1, 1.5)));
  EXPECT_NEAR(RotationAngle(mid), 0.25, 1e-12);
  EXPECT_TRUE(Interpolate(a, b, 1.0).isApprox(b, 1e-12));
}

TEST(Se3Test, ExpAndLogAreInverse) {
  Eigen::Matrix<double, 6, 1> twist;
  twist << 0.3, -0.2, 0.9, 1.0, 2.0, -0.5;
  const Pose pose = Exp(twist);
  EXPECT_NEAR(RotationAngle(pose), twist.head<3>().norm(), 1e-12);
  EXPECT_TRUE(Log(pose).isApprox(twist, 1e-10));
}

TEST(Se3Test, ZeroQuaternionIsRefused) {
  EXPECT_THROW(MakePose(Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero()), Error);
  EXPECT_NEAR(RotationAngle(MakePose(Eigen::Quaterniond(0, 0, 0, 2), Eigen::Vector3d::Zero())),
              std::numbers::pi, 1e-9);
}

}  // namespace
}  // namespace noctua::geometry
