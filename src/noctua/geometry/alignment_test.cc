#include "noctua/geometry/alignment.h"

#include <gtest/gtest.h>

#include <random>

#include "noctua/util/error.h"

namespace noctua::geometry {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(int count) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i)
    points.emplace_back(uniform(random), uniform(random), uniform(random));
  return points;
}

TEST(AlignmentTest, RecoversAKnownSimilarityAndRigidMotion) {
  const auto source = RandomPoints(50);
  Similarity truth;
  truth.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  truth.translation = Eigen::Vector3d(0.5, -1.0, 3.0);
  truth.scale = 1.7;
  std::vector<Eigen::Vector3d> target;
  for (const auto& point : source) target.push_back(truth(point));

  const Similarity with_scale = AlignUmeyama(source, target, true);
  EXPECT_NEAR(with_scale.scale, 1.7, 1e-9);
  EXPECT_TRUE(with_scale.rotation.isApprox(truth.rotation, 1e-9));
  EXPECT_TRUE(with_scale.translation.isApprox(truth.translation, 1e-9));

  truth.scale = 1.0;
  target.clear();
  for (const auto& point : source) target.push_back(truth(point));
  const Similarity rigid = AlignUmeyama(source, target, false);
  EXPECT_DOUBLE_EQ(rigid.scale, 1.0);
  EXPECT_TRUE(rigid.rotation.isApprox(truth.rotation, 1e-9));
  EXPECT_TRUE(rigid.translation.isApprox(truth.translation, 1e-9));
}

TEST(AlignmentTest, DegenerateInputIsRefused) {
  const auto points = RandomPoints(2);
  EXPECT_THROW(AlignUmeyama(points, points, false), Error);
  EXPECT_THROW(AlignUmeyama(RandomPoints(4), RandomPoints(5), false), Error);
  const std::vector<Eigen::Vector3d> same(5, Eigen::Vector3d(1, 1, 1));
  EXPECT_THROW(AlignUmeyama(same, same, false), Error);
}

}  // namespace
}  // namespace noctua::geometry
