#include "noctua/slam/map.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "noctua/geometry/se3.h"
#include "noctua/testing/test_camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

// Two keyframes of six keypoints each, all with a depth of 2 m (observations weigh 2 each).
class MapReclaimTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const geometry::PinholeCamera camera = testing::TestCamera();
    std::vector<cv::KeyPoint> keypoints;
    for (int i = 0; i < kPoints; ++i) keypoints.emplace_back(100.0f + 50.0f * i, 200.0f, 31.0f);
    const cv::Mat descriptors(kPoints, 32, CV_8U, cv::Scalar(0));
    const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
    auto features =
        std::make_shared<const FrameFeatures>(keypoints, descriptors, depth, camera, 40.0, 0.1);
    first_ = map_.AddKeyFrame(Frame(0, 0.0, features));
    second_ = map_.AddKeyFrame(Frame(1, 1.0, features));
    for (int i = 0; i < kPoints; ++i) {
      MapPoint* point = map_.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.0, 2.0), first_);
      for (KeyFrame* keyframe : {first_, second_}) {
        keyframe->SetMapPoint(i, point);
        point->AddObservation(keyframe, i);
      }
      points_.push_back(point);
    }
  }

  static constexpr int kPoints = 6;
  Map map_;
  KeyFrame* first_ = nullptr;
  KeyFrame* second_ = nullptr;
  std::vector<MapPoint*> points_;
};

TEST_F(MapReclaimTest, GoodPointsAreNeverFreed) {
  EXPECT_EQ(map_.ReclaimMapPoints({}), 0);
  EXPECT_EQ(map_.NumMapPointsAllocated(), kPoints);
  EXPECT_EQ(map_.NumMapPoints(), kPoints);
}

// Culled points go unless something outside the map still holds them; a held point that was
// merged into another keeps that one too, since its holder may follow the chain.
TEST_F(MapReclaimTest, FreesCulledPointsThatNothingHolds) {
  points_[0]->SetBad();             // culled, nobody holds it: freed
  points_[1]->SetBad();             // culled but a frame still holds it: kept
  points_[2]->Replace(points_[3]);  // merged into 3: 2 is bad and held, 3 is good
  points_[3]->Replace(points_[4]);  // ...then 3 into 4: the chain 2 -> 3 -> 4
  const std::vector<MapPoint*> held = {points_[1], points_[2], nullptr};
  EXPECT_EQ(map_.NumMapPoints(), 2);  // 4 and 5
  const int freed = map_.ReclaimMapPoints({&held});
  EXPECT_EQ(freed, 1);  // only point 0
  EXPECT_EQ(map_.NumMapPointsAllocated(), kPoints - 1);
  EXPECT_EQ(map_.NumMapPointsCreated(), kPoints);
  // The chain is intact and readable (AddressSanitizer would flag a freed link).
  EXPECT_EQ(points_[2]->replaced(), points_[4]);
  EXPECT_TRUE(points_[3]->bad());

  // Once the frame lets go, the rest of the culled points go too; the good ones stay.
  EXPECT_EQ(map_.ReclaimMapPoints({}), 3);
  EXPECT_EQ(map_.NumMapPointsAllocated(), 2);
  EXPECT_EQ(map_.NumMapPoints(), 2);
  EXPECT_EQ(first_->map_point(4), points_[4]);
  EXPECT_EQ(first_->map_point(5), points_[5]);
  // New points get fresh ids: no id is reused after a point was freed.
  MapPoint* added = map_.AddMapPoint(Eigen::Vector3d::Zero(), first_);
  EXPECT_EQ(added->id(), kPoints);
}

// Both keyframes hold six points seen twice (with depth): an adjustment of the whole map frees
// them when six are asked for, holds them once a point is culled.
TEST_F(MapReclaimTest, KeyFramesHoldingTooFewPointsAreNotAdjusted) {
  EXPECT_EQ(KeyFramesToAdjust(map_, kPoints), (std::vector<KeyFrame*>{first_, second_}));
  EXPECT_TRUE(KeyFramesToAdjust(map_, kPoints + 1).empty());
  points_[0]->SetBad();
  EXPECT_TRUE(KeyFramesToAdjust(map_, kPoints).empty());
  EXPECT_EQ(KeyFramesToAdjust(map_, kPoints - 1), (std::vector<KeyFrame*>{first_, second_}));
}

// A culled keyframe gives its observations back: the points it leaves with one observation are
// culled (ORB-SLAM's rule), and freed by the next pass; the keyframe's slots are empty.
TEST_F(MapReclaimTest, PointsLeftByACulledKeyFrameAreFreed) {
  second_->SetBad();
  for (MapPoint* point : points_) EXPECT_TRUE(point->bad());
  for (MapPoint* point : second_->map_points()) EXPECT_EQ(point, nullptr);
  EXPECT_EQ(map_.ReclaimMapPoints({}), kPoints);
  EXPECT_EQ(map_.NumMapPointsAllocated(), 0);
  for (MapPoint* point : first_->map_points()) EXPECT_EQ(point, nullptr);
}

// A keyframe's features can be seen again (moved keypoints, the same ones in the same order),
// never swapped for another set, nor given back to a culled keyframe.
TEST_F(MapReclaimTest, FeaturesAreReplacedOnlyByAsManyKeyPoints) {
  const FrameFeatures& before = first_->features();
  const Eigen::Vector3d turn(0.0, 0.5, 0.0);  // rad/s
  auto moved = std::make_shared<const FrameFeatures>(
      before.AtMiddleRow(turn, Eigen::Vector3d::Zero(), 0.03));
  first_->ReplaceFeatures(moved);
  EXPECT_EQ(&first_->features(), moved.get());
  EXPECT_GT((first_->features().undistorted(0) - before.undistorted(0)).norm(), 0.1);
  const cv::Mat one(1, 32, CV_8U, cv::Scalar(0));
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
  auto fewer = std::make_shared<const FrameFeatures>(
      std::vector<cv::KeyPoint>{cv::KeyPoint(100.0f, 100.0f, 31.0f)}, one, depth,
      testing::TestCamera(), 40.0, 0.1);
  EXPECT_THROW(first_->ReplaceFeatures(fewer), Error);
  EXPECT_THROW(first_->ReplaceFeatures(nullptr), Error);
  second_->SetBad();
  EXPECT_THROW(second_->ReplaceFeatures(moved), Error);
}

// Features of one keypoint at 2 m, for keyframes whose poses alone matter.
std::shared_ptr<const FrameFeatures> OneKeyPointFeatures() {
  const std::vector<cv::KeyPoint> keypoints = {cv::KeyPoint(100.0f, 100.0f, 31.0f)};
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
  return std::make_shared<const FrameFeatures>(keypoints, cv::Mat(1, 32, CV_8U, cv::Scalar(0)),
                                               depth, testing::TestCamera(), 40.0, 0.1);
}

// Keyframes 0-3 with 2 and 3 culled: when the good ones move, each culled keyframe keeps its
// pose relative to the latest good one before it (here keyframe 1 for both), and nothing else
// moves.
TEST(CulledKeyFramePosesTest, CulledKeyFramesFollowTheLatestGoodKeyFrameBeforeThem) {
  const auto features = OneKeyPointFeatures();
  Map map;
  std::vector<KeyFrame*> keyframes;
  for (int i = 0; i < 4; ++i) {
    Frame frame(i, i, features);
    Eigen::Matrix<double, 6, 1> twist;
    twist << 0.1 * i, -0.05 * i, 0.02, 0.3 * i, 0.1, -0.2 * i;
    frame.pose_cw = geometry::Exp(twist);
    keyframes.push_back(map.AddKeyFrame(frame));
  }
  keyframes[2]->SetBad();
  keyframes[3]->SetBad();
  const geometry::Pose third_from_second =
      keyframes[2]->pose_cw() * keyframes[1]->pose_cw().inverse();
  const geometry::Pose fourth_from_second =
      keyframes[3]->pose_cw() * keyframes[1]->pose_cw().inverse();
  const geometry::Pose first = keyframes[0]->pose_cw();
  const geometry::Pose third = keyframes[2]->pose_cw();

  const CulledKeyFramePoses culled(map);
  Eigen::Matrix<double, 6, 1> move;
  move << 0.2, 0.1, -0.3, 0.5, -0.4, 0.25;
  keyframes[1]->set_pose_cw(geometry::Exp(move) * keyframes[1]->pose_cw());
  culled.Restore();

  EXPECT_TRUE((keyframes[2]->pose_cw() * keyframes[1]->pose_cw().inverse())
                  .isApprox(third_from_second, 1e-12));
  EXPECT_TRUE((keyframes[3]->pose_cw() * keyframes[1]->pose_cw().inverse())
                  .isApprox(fourth_from_second, 1e-12));
  EXPECT_FALSE(keyframes[2]->pose_cw().isApprox(third, 1e-3));  // it did move
  EXPECT_TRUE(keyframes[0]->pose_cw().isApprox(first, 1e-15));
}

// Keyframes along the x axis, all looking ahead (+z) but one turned 60 degrees about y, one
// culled and two at the same distance: of those looking within 30 degrees of the pose's axis, the
// nearest centres come first, equal distances in id order; turned and culled ones never come.
TEST(NearestViewpointsTest, NearestCentresAmongKeyFramesLookingTheSameWay) {
  const auto features = OneKeyPointFeatures();
  Map map;
  const auto add = [&](double x, double turn_deg) {
    Frame frame(static_cast<long>(map.all_keyframes().size()), 0.0, features);
    const geometry::Pose pose_wc = geometry::MakePose(
        Eigen::Quaterniond(Eigen::AngleAxisd(turn_deg * M_PI / 180.0, Eigen::Vector3d::UnitY())),
        Eigen::Vector3d(x, 0.0, 0.0));
    frame.pose_cw = pose_wc.inverse();
    return map.AddKeyFrame(frame);
  };
  KeyFrame* far = add(1.0, 0.0);
  KeyFrame* right = add(0.3, 10.0);
  KeyFrame* turned = add(0.0, 60.0);
  KeyFrame* culled = add(0.05, 0.0);
  KeyFrame* left = add(-0.3, -20.0);
  KeyFrame* near = add(0.1, 0.0);
  culled->SetBad();

  const geometry::Pose pose_cw = geometry::Pose::Identity();
  const double half_angle = 30.0 * M_PI / 180.0;
  EXPECT_EQ(NearestViewpoints(map, pose_cw, half_angle, 10),
            (std::vector<KeyFrame*>{near, right, left, far}));
  EXPECT_EQ(NearestViewpoints(map, pose_cw, half_angle, 2), (std::vector<KeyFrame*>{near, right}));
  EXPECT_TRUE(NearestViewpoints(map, pose_cw, half_angle, 0).empty());
  // A wider gate lets the turned keyframe in, nearest of all.
  EXPECT_EQ(NearestViewpoints(map, pose_cw, 70.0 * M_PI / 180.0, 1).front(), turned);
  // Seen from the turned pose, only the turned keyframe looks the same way.
  EXPECT_EQ(NearestViewpoints(map, turned->pose_cw(), half_angle, 10),
            (std::vector<KeyFrame*>{turned}));
}

}  // namespace
}  // namespace noctua::slam
