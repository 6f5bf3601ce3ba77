#include "noctua/slam/local_mapping.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <memory>
#include <random>
#include <vector>

#include "noctua/slam/map.h"
#include "noctua/testing/test_camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

constexpr double kBf = 40.0;

using testing::TestCamera;

// One scene point: where it is, whether each keyframe reads a depth for it, and whether it is
// already a map point (from depth) observed by both keyframes.
struct ScenePoint {
  Eigen::Vector3d position;
  bool depth_first = false;
  bool depth_second = false;
  bool mapped = false;
  int octave_second = 0;  // pyramid level of its keypoint in the second keyframe
};

// Two keyframes seeing a generated scene with exact keypoints and a distinct descriptor per
// scene point, so that the answer is known: keypoint k of both keyframes is scene point k.
class TriangulationScene {
 public:
  TriangulationScene(std::vector<ScenePoint> scene, const geometry::Pose& second_pose_cw)
      : scene_(std::move(scene)), pyramid_(1.2, 8) {
    descriptors_ = cv::Mat(static_cast<int>(scene_.size()), 32, CV_8U);
    cv::randu(descriptors_, cv::Scalar(0), cv::Scalar(256));
    first_ = map_.AddKeyFrame(MakeFrame(0, geometry::Pose::Identity(), true));
    second_ = map_.AddKeyFrame(MakeFrame(1, second_pose_cw, false));
    for (std::size_t k = 0; k < scene_.size(); ++k) {
      if (!scene_[k].mapped) continue;
      MapPoint* point = map_.AddMapPoint(scene_[k].position, first_);
      for (KeyFrame* keyframe : {first_, second_}) {
        keyframe->SetMapPoint(static_cast<int>(k), point);
        point->AddObservation(keyframe, static_cast<int>(k));
      }
      point->UpdateDescriptor();
      point->UpdateNormalAndDepth(pyramid_);
    }
    first_->UpdateConnections();
  }

  // Runs the triangulation stage for the second keyframe.
  int Triangulate(const SlamOptions& options) {
    LocalMapper mapper(options, pyramid_);
    return mapper.CreateTriangulatedPoints(second_, map_);
  }

  const std::vector<ScenePoint>& scene() const { return scene_; }
  KeyFrame* first() const { return first_; }
  KeyFrame* second() const { return second_; }

 private:
  Frame MakeFrame(long id, const geometry::Pose& pose_cw, bool first) {
    const geometry::PinholeCamera camera = TestCamera();
    std::vector<cv::KeyPoint> keypoints;
    std::vector<double> depth, right_u;
    for (const ScenePoint& point : scene_) {
      const Eigen::Vector3d in_camera = pose_cw * point.position;
      const Eigen::Vector2d pixel = camera.Project(in_camera);
      keypoints.emplace_back(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()), 31.0f,
                             0.0f, 0.0f, first ? 0 : point.octave_second);
      const bool has_depth = first ? point.depth_first : point.depth_second;
      depth.push_back(has_depth ? in_camera.z() : 0.0);
      right_u.push_back(has_depth ? pixel.x() - kBf / in_camera.z() : -1.0);
    }
    auto features =
        std::make_shared<const FrameFeatures>(keypoints, descriptors_, depth, right_u, camera);
    Frame frame(id, static_cast<double>(id), features);
    frame.pose_cw = pose_cw;
    return frame;
  }

  std::vector<ScenePoint> scene_;
  ScalePyramid pyramid_;
  cv::Mat descriptors_;
  Map map_;
  KeyFrame* first_ = nullptr;
  KeyFrame* second_ = nullptr;
};

// 40 points with depth already mapped (they link the keyframes and give the scene depth), 60
// points 4-8 m away without depth (or, for a third of them, with a depth beyond close_depth_m),
// and 20 points 300 m away that the baseline cannot place.
std::vector<ScenePoint> GeneratedScene() {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> lateral(-0.5, 0.5);
  std::vector<ScenePoint> scene;
  auto add = [&](double depth, bool depth_first, bool depth_second, bool mapped) {
    ScenePoint point;
    point.position = Eigen::Vector3d(lateral(random) * depth, 0.7 * lateral(random) * depth, depth);
    point.depth_first = depth_first;
    point.depth_second = depth_second;
    point.mapped = mapped;
    scene.push_back(point);
  };
  std::uniform_real_distribution<double> near(1.5, 2.5), middle(4.0, 8.0);
  for (int k = 0; k < 40; ++k) add(near(random), true, true, true);
  for (int k = 0; k < 60; ++k) add(middle(random), k % 3 == 0, k % 3 == 1, false);
  for (int k = 0; k < 20; ++k) add(300.0, false, false, false);
  return scene;
}

// The second camera `baseline_m` away from the first, mostly to the side, turned by 2 degrees.
geometry::Pose SecondPose(double baseline_m) {
  geometry::Pose pose_wc = geometry::Pose::Identity();
  pose_wc.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  pose_wc.translation() = baseline_m * Eigen::Vector3d(1.0, 0.07, 0.17).normalized();
  return pose_wc.inverse();
}

TEST(TriangulationTest, PlacesPointsWithoutDepthAndRejectsThoseWithTooLittleParallax) {
  TriangulationScene scene(GeneratedScene(), SecondPose(0.3));
  const int created = scene.Triangulate(SlamOptions());
  int middle = 0, far = 0;
  for (int k = 0; k < static_cast<int>(scene.scene().size()); ++k) {
    const ScenePoint& truth = scene.scene()[static_cast<std::size_t>(k)];
    MapPoint* point = scene.second()->map_point(k);
    if (truth.mapped) continue;
    if (point == nullptr) continue;
    ASSERT_EQ(scene.first()->map_point(k), point) << "keypoint " << k;
    EXPECT_EQ(point->num_observations(), 2);
    // Exact keypoints: linear triangulation (or a depth reading) gives the point back.
    EXPECT_LT((point->position() - truth.position).norm(), 1e-3 * truth.position.z())
        << "keypoint " << k;
    EXPECT_GT(point->max_distance(), 0.0);
    if (truth.position.z() > 100.0) {
      ++far;
    } else {
      ++middle;
    }
  }
  EXPECT_EQ(created, middle + far);
  EXPECT_EQ(middle, 60);  // every point without usable depth, and those with depth beyond 3.1 m
  EXPECT_EQ(far, 0);      // 0.3 m at 300 m: a cosine of 0.9999995, above 0.9998
}

TEST(TriangulationTest, SkipsAPairWhoseBaselineIsTooSmallForTheSceneDepth) {
  // 1.5 cm against a median scene depth of about 2 m: below 1 %.
  TriangulationScene scene(GeneratedScene(), SecondPose(0.015));
  EXPECT_EQ(scene.Triangulate(SlamOptions()), 0);
}

TEST(TriangulationTest, LeavesKeypointsWithCloseDepthToDepth) {
  // The middle points get a depth within close_depth_m in the new keyframe: not candidates (the
  // far ones, without depth, have too little parallax).
  std::vector<ScenePoint> points = GeneratedScene();
  SlamOptions options;
  options.close_depth_m = 10.0;
  for (ScenePoint& point : points) {
    if (!point.mapped && point.position.z() < 10.0) point.depth_second = true;
  }
  TriangulationScene scene(points, SecondPose(0.3));
  EXPECT_EQ(scene.Triangulate(options), 0);
}

TEST(TriangulationTest, RejectsPairsWhoseScalesDisagree) {
  // The new keyframe sees the points without depth at pyramid level 5 (2.5 times coarser) from
  // about the same distance as the first keyframe at level 0: not the same physical feature.
  std::vector<ScenePoint> points = GeneratedScene();
  for (ScenePoint& point : points) point.octave_second = point.mapped ? 0 : 5;
  TriangulationScene scene(points, SecondPose(0.3));
  EXPECT_EQ(scene.Triangulate(SlamOptions()), 0);
}

TEST(TriangulationTest, OptionsCheckRejectsBadThresholds) {
  SlamOptions options;
  options.triangulation.max_parallax_cos = 1.0;
  EXPECT_THROW(options.Check(), Error);
  options = SlamOptions();
  options.triangulation.covisibles = 0;
  EXPECT_THROW(options.Check(), Error);
  options = SlamOptions();
  options.max_depth_m = 0.05;
  EXPECT_THROW(options.Check(), Error);
}

// The mapped points of the generated scene (seen by both keyframes, with depth), each moved by
// 2 cm, and the second keyframe moved by 3 cm: the bundle adjustment has something to undo.
std::vector<MapPoint*> PerturbMappedPoints(TriangulationScene& scene) {
  std::vector<MapPoint*> points;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> offset(-0.02, 0.02);
  for (int k = 0; k < static_cast<int>(scene.scene().size()); ++k) {
    MapPoint* point = scene.second()->map_point(k);
    if (point == nullptr) continue;
    point->set_position(point->position() +
                        Eigen::Vector3d(offset(random), offset(random), offset(random)));
    points.push_back(point);
  }
  geometry::Pose moved = scene.second()->pose_cw();
  moved.translation() += Eigen::Vector3d(0.03, -0.01, 0.02);
  scene.second()->set_pose_cw(moved);
  return points;
}

TEST(BackgroundBundleAdjustmentTest, ChangesTheMapOnlyWhenAppliedAfterItsSolve) {
  const ScalePyramid pyramid(1.2, 8);
  TriangulationScene scene(GeneratedScene(), SecondPose(0.4));
  const std::vector<MapPoint*> points = PerturbMappedPoints(scene);
  ASSERT_EQ(points.size(), 40u);
  const geometry::Pose truth = SecondPose(0.4);
  const geometry::Pose moved = scene.second()->pose_cw();
  const Eigen::Vector3d moved_point = points[1]->position();
  const std::unique_ptr<BundleAdjustment> adjustment =
      BundleAdjustment::Local(scene.second(), pyramid, kBf, 20, 20);
  EXPECT_EQ(adjustment->points().size(), 40u);
  adjustment->Apply(pyramid);  // before Solve: nothing happens
  EXPECT_EQ(scene.second()->pose_cw().matrix(), moved.matrix());
  adjustment->Solve();  // on its copies only
  EXPECT_EQ(scene.second()->pose_cw().matrix(), moved.matrix());
  EXPECT_EQ(points[1]->position(), moved_point);
  adjustment->Apply(pyramid);
  const double before = (moved.translation() - truth.translation()).norm();
  const double after = (scene.second()->pose_cw().translation() - truth.translation()).norm();
  EXPECT_LT(after, 0.2 * before);
  EXPECT_NE(points[1]->position(), moved_point);
}

TEST(BackgroundBundleAdjustmentTest, LeavesAPointCulledWhileItSolved) {
  const ScalePyramid pyramid(1.2, 8);
  TriangulationScene scene(GeneratedScene(), SecondPose(0.4));
  const std::vector<MapPoint*> points = PerturbMappedPoints(scene);
  const std::unique_ptr<BundleAdjustment> adjustment =
      BundleAdjustment::Local(scene.second(), pyramid, kBf, 20, 20);
  adjustment->Solve();
  // The map goes on while the solve runs: a point is culled.
  const Eigen::Vector3d culled_position = points[0]->position();
  points[0]->SetBad();
  adjustment->Apply(pyramid);
  EXPECT_EQ(points[0]->position(), culled_position);
  EXPECT_TRUE(points[0]->bad());
  for (int k = 0; k < scene.second()->features().size(); ++k) {
    EXPECT_NE(scene.second()->map_point(k), points[0]);
  }
  EXPECT_FALSE(points[1]->bad());
}

TEST(BackgroundBundleAdjustmentTest, TheMapperHoldsItsPointsUntilItLandsIt) {
  const ScalePyramid pyramid(1.2, 8);
  TriangulationScene scene(GeneratedScene(), SecondPose(0.4));
  PerturbMappedPoints(scene);
  const geometry::Pose moved = scene.second()->pose_cw();
  SlamOptions options;
  options.background_bundle_adjustment = true;
  options.triangulation.enabled = false;
  options.bf = kBf;
  LocalMapper mapper(options, pyramid);
  Map unused;
  mapper.ProcessKeyFrame(scene.second(), unused);
  EXPECT_EQ(mapper.pending_points().size(), 40u);                 // held until it lands
  EXPECT_EQ(scene.second()->pose_cw().matrix(), moved.matrix());  // not applied yet
  EXPECT_TRUE(mapper.CollectBundleAdjustment(/*wait=*/true));
  EXPECT_TRUE(mapper.pending_points().empty());
  const geometry::Pose truth = SecondPose(0.4);
  EXPECT_LT((scene.second()->pose_cw().translation() - truth.translation()).norm(), 0.006);
  EXPECT_TRUE(mapper.CollectBundleAdjustment(/*wait=*/false));  // nothing left
}

}  // namespace
}  // namespace noctua::slam
