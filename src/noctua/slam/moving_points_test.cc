#include "noctua/slam/moving_points.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "noctua/geometry/camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

constexpr double kSigma = 0.01;

// Points of a room 1-5 m in front of the camera, seen after a camera motion `world_to_camera`;
// the points of `movers` (each a body with its own motion) are seen where their body took them.
struct Scene {
  std::vector<PointPair> pairs;
  std::vector<bool> truly_static;
};

Eigen::Isometry3d Motion(double angle_deg, const Eigen::Vector3d& axis,
                         const Eigen::Vector3d& translation) {
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis.normalized()).matrix();
  motion.translation() = translation;
  return motion;
}

void AddBody(Scene& scene, std::mt19937& rng, int count, const Eigen::Vector3d& centre,
             double extent, const Eigen::Isometry3d& seen_from, bool is_static) {
  std::uniform_real_distribution<double> spread(-extent, extent);
  std::normal_distribution<double> noise(0.0, kSigma);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d point = centre + Eigen::Vector3d(spread(rng), spread(rng), spread(rng));
    PointPair pair;
    pair.map = point;
    pair.seen = seen_from * point + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    pair.sigma_m = kSigma;
    scene.pairs.push_back(pair);
    scene.truly_static.push_back(is_static);
  }
}

// How many static and how many moving points FindStaticPairs keeps.
std::pair<int, int> KeptPoints(const Scene& scene) {
  const std::vector<bool> is_static = FindStaticPairs(scene.pairs, RigidityOptions());
  int kept_static = 0, kept_moving = 0;
  for (std::size_t i = 0; i < is_static.size(); ++i) {
    if (is_static[i] && scene.truly_static[i]) ++kept_static;
    if (is_static[i] && !scene.truly_static[i]) ++kept_moving;
  }
  return {kept_static, kept_moving};
}

TEST(FindStaticPairs, KeepsTheRoomAndDropsAPersonWhoCoversAThirdOfTheView) {
  std::mt19937 rng(7);
  const Eigen::Isometry3d camera = Motion(8.0, {0.2, 1.0, 0.1}, {0.3, -0.1, 0.2});
  Scene scene;
  AddBody(scene, rng, 200, {0.0, 0.0, 3.0}, 1.5, camera, true);
  // The person walked 15 cm while the camera moved: seen where camera * walk puts them.
  AddBody(scene, rng, 100, {0.2, 0.0, 1.5}, 0.25, camera * Motion(0.0, {0, 1, 0}, {0.15, 0, 0}),
          false);
  const auto [kept_static, kept_moving] = KeptPoints(scene);
  EXPECT_GE(kept_static, 195);  // 3-sigma agreement: a few static points may fall out
  EXPECT_LE(kept_moving, 5);    // points near the axis of the walk barely move against the room
}

TEST(FindStaticPairs, ThreePeopleTogetherLargerThanTheRoomStillLoseToIt) {
  // Each person is a body of their own: the room is the largest rigid set although the people's
  // points outnumber its points.
  std::mt19937 rng(11);
  const Eigen::Isometry3d camera = Motion(3.0, {1.0, 0.3, 0.0}, {0.05, 0.02, -0.1});
  Scene scene;
  AddBody(scene, rng, 120, {0.0, 0.0, 3.5}, 1.5, camera, true);
  AddBody(scene, rng, 70, {-0.8, 0.0, 1.5}, 0.25, camera * Motion(0, {0, 1, 0}, {0.2, 0, 0}),
          false);
  AddBody(scene, rng, 70, {0.0, 0.1, 2.0}, 0.25, camera * Motion(0, {0, 1, 0}, {-0.2, 0, 0.1}),
          false);
  AddBody(scene, rng, 70, {0.8, 0.0, 1.2}, 0.25, camera * Motion(20, {0, 1, 0}, {0, 0, 0.2}),
          false);
  const auto [kept_static, kept_moving] = KeptPoints(scene);
  EXPECT_GE(kept_static, 115);
  EXPECT_LE(kept_moving, 10);
}

TEST(FindStaticPairs, AStaticSceneLosesNothingAndTooFewPairsDecideNothing) {
  std::mt19937 rng(3);
  Scene scene;
  AddBody(scene, rng, 300, {0.0, 0.0, 2.5}, 1.5, Motion(30.0, {0, 1, 0}, {1.0, 0.0, 0.5}), true);
  const std::vector<bool> is_static = FindStaticPairs(scene.pairs, RigidityOptions());
  EXPECT_GE(std::count(is_static.begin(), is_static.end(), true), 295);

  // A wrong match (a point seen 0.5 m from where it is) is dropped like a mover.
  scene.pairs[0].seen += Eigen::Vector3d(0.5, 0.0, 0.0);
  EXPECT_FALSE(FindStaticPairs(scene.pairs, RigidityOptions())[0]);

  scene.pairs.resize(5);
  scene.pairs[1].seen += Eigen::Vector3d(2.0, 0.0, 0.0);
  const std::vector<bool> few = FindStaticPairs(scene.pairs, RigidityOptions());
  EXPECT_EQ(std::count(few.begin(), few.end(), true), 5);

  RigidityOptions bad;
  bad.min_core_agreement = 0.0;
  EXPECT_THROW(FindStaticPairs(scene.pairs, bad), Error);
}

// A frame of keypoints on a grid: a person 0.6 m wide at 1.5 m in the middle, the wall at 3 m.
FrameFeatures PersonInFrontOfAWall(std::vector<int>& on_person) {
  const geometry::PinholeCamera camera(
      {.fx = 500, .fy = 500, .cx = 320, .cy = 240, .width = 640, .height = 480},
      geometry::Distortion());
  const cv::Rect person(220, 40, 200, 440);  // 0.6 m x 1.3 m at 1.5 m
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(3.0f));
  depth(person).setTo(1.5f);
  std::vector<cv::KeyPoint> keypoints;
  for (int y = 20; y < 480; y += 40) {
    for (int x = 20; x < 640; x += 40) {
      if (person.contains({x, y})) on_person.push_back(static_cast<int>(keypoints.size()));
      keypoints.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), 31.0f);
    }
  }
  const cv::Mat descriptors(static_cast<int>(keypoints.size()), 32, CV_8U, cv::Scalar(0));
  return FrameFeatures(keypoints, descriptors, depth, camera, 40.0, 0.1);
}

TEST(GrowMovingRegions, ThreeMovingPointsTakeThePersonButNotTheWall) {
  std::vector<int> on_person;
  const FrameFeatures features = PersonInFrontOfAWall(on_person);
  ASSERT_GT(on_person.size(), 30u);
  std::vector<bool> moving(static_cast<std::size_t>(features.size()), false);
  // Three moving points on the chest.
  const int chest = on_person[on_person.size() / 3];
  for (int k : {chest - 1, chest, chest + 1}) moving[static_cast<std::size_t>(k)] = true;
  // Judged: the three and three static ones elsewhere on the person.
  std::vector<bool> judged = moving;
  for (int k : {on_person[0], on_person[1], on_person.back()}) {
    judged[static_cast<std::size_t>(k)] = true;
  }
  std::vector<bool> grown = moving;
  GrowMovingRegions(features, MovingRegion(), judged, grown);
  int person_flagged = 0;
  for (int k : on_person) person_flagged += grown[static_cast<std::size_t>(k)] ? 1 : 0;
  // The region reaches 0.3 m either side and 0.9 m up and down: at 1.5 m the whole body but the
  // feet; the wall, 1.5 m behind, is not at the person's depth.
  EXPECT_GE(person_flagged, static_cast<int>(on_person.size() * 3 / 4));
  EXPECT_EQ(std::count(grown.begin(), grown.end(), true), person_flagged);

  // A single flagged point (a wrong match) grows nothing.
  std::vector<bool> single(moving.size(), false);
  single[static_cast<std::size_t>(chest)] = true;
  GrowMovingRegions(features, MovingRegion(), judged, single);
  EXPECT_EQ(std::count(single.begin(), single.end(), true), 1);

  // Three moving among many judged static (a blurred, static scene): nothing grows.
  std::vector<bool> many(moving.size(), true);
  std::vector<bool> few = moving;
  GrowMovingRegions(features, MovingRegion(), many, few);
  EXPECT_EQ(std::count(few.begin(), few.end(), true), 3);
}

// Known values: P(X >= 2) for 3 fair coins is 1/2; P(X >= 3) is 1/8; the whole range is 1.
TEST(BinomialTailAtLeast, MatchesKnownValues) {
  EXPECT_NEAR(BinomialTailAtLeast(2, 3, 0.5), 0.5, 1e-12);
  EXPECT_NEAR(BinomialTailAtLeast(3, 3, 0.5), 0.125, 1e-12);
  EXPECT_DOUBLE_EQ(BinomialTailAtLeast(0, 10, 0.3), 1.0);
  EXPECT_DOUBLE_EQ(BinomialTailAtLeast(11, 10, 0.3), 0.0);
  // 5 of 20 at p = 0.1: 1 - P(X <= 4) = 0.04317 (binomial table).
  EXPECT_NEAR(BinomialTailAtLeast(5, 20, 0.1), 0.04317, 1e-5);
}

// Three moving keypoints on the chest, all that was judged on the person. Outside the person the
// judged wall keypoints fail now rarely (a clear mover: the region grows), now as often (three
// failures are no more than the frame's usual: with max_chance, it does not).
TEST(GrowMovingRegions, WithMaxChanceGrowsOnlyOnMoreFailuresThanElsewhere) {
  std::vector<int> on_person;
  const FrameFeatures features = PersonInFrontOfAWall(on_person);
  const std::size_t n = static_cast<std::size_t>(features.size());
  std::vector<bool> on_person_flag(n, false);
  for (int k : on_person) on_person_flag[static_cast<std::size_t>(k)] = true;
  const int chest = on_person[on_person.size() / 3];
  std::vector<bool> seeds(n, false);
  for (int k : {chest - 1, chest, chest + 1}) seeds[static_cast<std::size_t>(k)] = true;
  const auto grown_with = [&](int failing_wall_points, double max_chance) {
    std::vector<bool> judged = seeds;
    std::vector<bool> moving = seeds;
    int judged_wall = 0, failing = 0;
    for (std::size_t k = 0; k < n && judged_wall < 40; ++k) {
      if (on_person_flag[k]) continue;
      judged[k] = true;
      ++judged_wall;
      if (failing < failing_wall_points) {
        moving[k] = true;
        ++failing;
      }
    }
    MovingRegion region;
    region.max_chance = max_chance;
    GrowMovingRegions(features, region, judged, moving);
    int person_flagged = 0;
    for (int k : on_person) person_flagged += moving[static_cast<std::size_t>(k)] ? 1 : 0;
    return person_flagged;
  };
  const int person = static_cast<int>(on_person.size());
  // One wall failure in 40: three of three on the chest are no chance (0.05^3).
  EXPECT_GE(grown_with(1, 0.01), person * 3 / 4);
  // Twenty in 40 (spread along the top rows, none three in a region of the person's depth): at a
  // rate of one half, three of three happen one time in eight.
  EXPECT_EQ(grown_with(20, 0.01), 3);
  // Without the chance test the region grows either way.
  EXPECT_GE(grown_with(20, 1.0), person * 3 / 4);
}

TEST(LiftedPointSigma, GrowsWithDepthAndPyramidLevel) {
  EXPECT_GT(LiftedPointSigma(4.0, 1.0, 525.0), 4.0 * LiftedPointSigma(1.0, 1.0, 525.0));
  EXPECT_GT(LiftedPointSigma(1.0, 2.0, 525.0), LiftedPointSigma(1.0, 1.0, 525.0));
  // At 1 m: 1.9 mm axial noise and 1.9 mm per pixel across the ray.
  EXPECT_NEAR(LiftedPointSigma(1.0, 1.0, 525.0), 0.0034, 0.0002);
}

// Two frames 0.4 s apart of a wall 3 m away and a person who walked from 1.5 to 1.9 m away; 20
// wall keypoints of the second frame look different (fresh descriptors) and cannot be matched.
// Proven static: exactly the wall keypoints matched over the baseline; the person moved, the 20
// were never judged. With `skip_depth_edges`, nor were those on the person's outline (within two
// pixels of it, either side), where the depth jumps.
void ExpectProvenStaticOnlyWhereMatched(const MotionSegmenterOptions& options) {
  const geometry::PinholeCamera camera(
      {.fx = 500, .fy = 500, .cx = 320, .cy = 240, .width = 640, .height = 480},
      geometry::Distortion());
  const cv::Rect person(220, 40, 200, 440);
  std::vector<cv::KeyPoint> keypoints;
  for (int y = 20; y < 480; y += 40) {
    for (int x = 20; x < 640; x += 40) {
      keypoints.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), 31.0f);
    }
  }
  const int count = static_cast<int>(keypoints.size());
  cv::Mat descriptors(count, 32, CV_8U);
  cv::RNG rng(7);
  rng.fill(descriptors, cv::RNG::UNIFORM, 0, 256);
  const auto frame = [&](float person_depth, const cv::Mat& rows) {
    cv::Mat depth(480, 640, CV_32F, cv::Scalar(3.0f));
    depth(person).setTo(person_depth);
    return std::make_shared<const FrameFeatures>(keypoints, rows, depth, camera, 40.0, 0.1);
  };
  std::vector<bool> on_person(static_cast<std::size_t>(count), false);
  std::vector<bool> unmatched(static_cast<std::size_t>(count), false);
  cv::Mat later = descriptors.clone();
  int fresh = 0;
  for (int i = 0; i < count; ++i) {
    on_person[static_cast<std::size_t>(i)] =
        person.contains(keypoints[static_cast<std::size_t>(i)].pt);
    if (!on_person[static_cast<std::size_t>(i)] && fresh < 20 && i % 3 == 0) {
      rng.fill(later.row(i), cv::RNG::UNIFORM, 0, 256);
      unmatched[static_cast<std::size_t>(i)] = true;
      ++fresh;
    }
  }
  MotionSegmenter segmenter(options, ScalePyramid(1.2, 8));
  EXPECT_FALSE(segmenter.FlagMoving(frame(1.5f, descriptors), 0.0).whole_baseline);
  const MotionVerdicts verdicts = segmenter.FlagMoving(frame(1.9f, later), 0.4);
  ASSERT_TRUE(verdicts.whole_baseline);
  const std::vector<bool>& moving = verdicts.moving;
  const std::vector<bool>& proven = verdicts.proven_static;
  ASSERT_EQ(proven.size(), static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < proven.size(); ++i) {
    const cv::Point2f& point = keypoints[i].pt;
    const cv::Rect outline_band(person.x - 2, person.y - 2, person.width + 4, person.height + 4);
    const cv::Rect inner(person.x + 3, person.y + 3, person.width - 6, person.height - 6);
    const bool on_outline = outline_band.contains(point) && !inner.contains(point);
    const bool unjudged = unmatched[i] || (options.skip_depth_edges && on_outline);
    EXPECT_EQ(proven[i], !on_person[i] && !unjudged) << "keypoint " << i;
    if (on_person[i]) {
      EXPECT_TRUE(moving[i]) << "keypoint " << i;
    }
  }
}

TEST(MotionSegmenter, ProvesStaticOnlyTheKeypointsMatchedOverTheBaseline) {
  ExpectProvenStaticOnlyWhereMatched(MotionSegmenterOptions());
}

TEST(MotionSegmenter, BehindADetectorLeavesTheDepthEdgesUnjudged) {
  const MotionSegmenterOptions options = MotionSegmenterOptions::BehindDetector();
  ASSERT_TRUE(options.skip_depth_edges);
  ExpectProvenStaticOnlyWhereMatched(options);
}

}  // namespace
}  // namespace noctua::slam
