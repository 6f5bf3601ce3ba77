#include "noctua/slam/frame.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "noctua/testing/test_camera.h"
#include "noctua/util/error.h"

namespace noctua::slam {
namespace {

constexpr double kBf = 40.0;
constexpr double kReadoutS = 0.02;

// Keypoints in the test camera's middle column (x = cx = 320) on the first row, the middle row
// and the last row (y = 0, 240, 478), all at 2 m, and a fourth on the last row without depth.
FrameFeatures ThreeRowsAndOneWithoutDepth() {
  const std::vector<cv::KeyPoint> keypoints = {{320.0f, 0.0f, 31.0f},
                                               {320.0f, 240.0f, 31.0f},
                                               {320.0f, 478.0f, 31.0f},
                                               {320.0f, 478.0f, 31.0f}};
  const cv::Mat descriptors(4, 32, CV_8U, cv::Scalar(0));
  const std::vector<double> depth = {2.0, 2.0, 2.0, 0.0};
  std::vector<double> right_u;
  for (double d : depth) right_u.push_back(d > 0.0 ? 320.0 - kBf / d : -1.0);
  return FrameFeatures(keypoints, descriptors, depth, right_u, testing::TestCamera());
}

// A box 1 m away in front of a wall 2.5 m away, its left side at x = 300, with a hole in the wall
// at (100, 100) and a speckle of sensor noise (+2 mm, well within 4 sigmas) around (400, 300).
// Keypoints on the box's edge, next to it on the wall, and next to the hole are on depth edges;
// those a few pixels off either side of the edge, in the speckle and far from all are not.
TEST(FrameFeatures, MarksKeypointsWhereTheDepthJumpsOrHasAHole) {
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.5f));
  depth(cv::Rect(300, 0, 340, 480)).setTo(1.0f);
  depth.at<float>(100, 100) = 0.0f;
  depth(cv::Rect(399, 299, 3, 3)).setTo(1.002f);
  const std::vector<std::pair<cv::Point2f, bool>> cases = {
      {{300.0f, 240.0f}, true},   // on the box, its edge within the neighbourhood
      {{298.0f, 240.0f}, true},   // on the wall, the box two pixels away
      {{297.0f, 240.0f}, false},  // on the wall, three pixels from the box
      {{303.0f, 240.0f}, false},  // on the box, three pixels in
      {{102.0f, 101.0f}, true},   // the hole within two pixels
      {{103.0f, 100.0f}, false},  // the hole three pixels away
      {{400.0f, 300.0f}, false},  // noise on one surface is no edge
      {{0.0f, 0.0f}, false},      // the image's corner: the neighbourhood is cut, not a hole
      {{100.0f, 100.0f}, false},  // in the hole: no depth, nothing to judge
  };
  std::vector<cv::KeyPoint> keypoints;
  for (const auto& [point, edge] : cases) keypoints.emplace_back(point, 31.0f);
  const cv::Mat descriptors(static_cast<int>(keypoints.size()), 32, CV_8U, cv::Scalar(0));
  const FrameFeatures features(keypoints, descriptors, depth, testing::TestCamera(), kBf, 0.1);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    EXPECT_EQ(features.OnDepthEdge(static_cast<int>(i)), cases[i].second)
        << "keypoint at " << cases[i].first;
  }
  EXPECT_EQ(features.depth(8), 0.0);
  // The flags survive moving to the middle row; features restored without them have none.
  const FrameFeatures moved = features.AtMiddleRow({0.0, 1.0, 0.0}, {0.0, 0.0, 0.0}, kReadoutS);
  for (int i = 0; i < features.size(); ++i) {
    EXPECT_EQ(moved.OnDepthEdge(i), features.OnDepthEdge(i));
  }
  const FrameFeatures restored = ThreeRowsAndOneWithoutDepth();
  for (int i = 0; i < restored.size(); ++i) EXPECT_FALSE(restored.OnDepthEdge(i));
}

// Row y is read (y / 480 - 1/2) * readout after the middle row.
double RowTime(double y) { return (y / 480.0 - 0.5) * kReadoutS; }

// Turning about the camera's y axis at w rad/s, a point in the middle column (camera x = 0)
// moves in camera coordinates by (w x p) dt = (w z dt, 0, 0): its pixel by 500 w dt. Each
// keypoint goes back by its row's dt: right on the first row (read before the middle one), left
// on the last, the middle row stays.
TEST(FrameFeaturesAtMiddleRow, UndoesAKnownTurnRowByRow) {
  const FrameFeatures seen = ThreeRowsAndOneWithoutDepth();
  const double w = 2.0;  // rad/s, about 115 deg/s: fr1/rpy's fastest turns
  const FrameFeatures moved = seen.AtMiddleRow({0.0, w, 0.0}, Eigen::Vector3d::Zero(), kReadoutS);
  EXPECT_NEAR(moved.undistorted(0).x(), 320.0 + 10.0, 1e-9);  // 500 px * 2 rad/s * 10 ms
  EXPECT_NEAR(moved.undistorted(1).x(), 320.0, 1e-9);
  EXPECT_NEAR(moved.undistorted(2).x(), 320.0 - 500.0 * w * RowTime(478.0), 1e-9);
  // Without depth the point is moved along its ray: a turn moves every depth alike.
  EXPECT_NEAR(moved.undistorted(3).x(), moved.undistorted(2).x(), 1e-9);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(moved.undistorted(i).y(), seen.undistorted(i).y(), 1e-9);
    // The keypoints as detected and their depth stay; the right coordinate moves with u.
    EXPECT_EQ(moved.keypoint(i).pt, seen.keypoint(i).pt);
    EXPECT_EQ(moved.depth(i), seen.depth(i));
    if (seen.depth(i) > 0.0) {
      EXPECT_NEAR(moved.right_u(i) - moved.undistorted(i).x(),
                  seen.right_u(i) - seen.undistorted(i).x(), 1e-9);
    }
  }
  // The search grid follows the moved positions.
  EXPECT_EQ(moved.InArea(moved.undistorted(2).x(), 478.0, 1.0), (std::vector<int>{2, 3}));
  EXPECT_TRUE(moved.InArea(320.0, 478.0, 2.0).empty());
}

// A sideways translation v moves a point at depth z by v dt / z in normalised coordinates; a
// keypoint without depth cannot be moved by it and stays.
TEST(FrameFeaturesAtMiddleRow, UndoesATranslationWhereThereIsDepth) {
  const FrameFeatures seen = ThreeRowsAndOneWithoutDepth();
  const double v = 1.0;  // m/s along x
  const FrameFeatures moved = seen.AtMiddleRow(Eigen::Vector3d::Zero(), {v, 0.0, 0.0}, kReadoutS);
  EXPECT_NEAR(moved.undistorted(0).x(), 320.0 + 2.5, 1e-9);  // 500 px * 1 m/s * 10 ms / 2 m
  EXPECT_NEAR(moved.undistorted(1).x(), 320.0, 1e-9);
  EXPECT_NEAR(moved.undistorted(2).x(), 320.0 - 500.0 * v * RowTime(478.0) / 2.0, 1e-9);
  EXPECT_NEAR(moved.undistorted(3).x(), 320.0, 1e-9);
}

// A global shutter (readout 0) or a camera at rest changes nothing.
TEST(FrameFeaturesAtMiddleRow, ChangesNothingWithoutReadoutOrMotion) {
  const FrameFeatures seen = ThreeRowsAndOneWithoutDepth();
  for (const FrameFeatures& moved :
       {seen.AtMiddleRow({0.0, 2.0, 0.0}, {1.0, 0.0, 0.0}, 0.0),
        seen.AtMiddleRow(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), kReadoutS)}) {
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(moved.undistorted(i), seen.undistorted(i));
      EXPECT_EQ(moved.right_u(i), seen.right_u(i));
    }
  }
}

// Restored features (map_io.h) keep the positions they are given, and refuse a count that does
// not match the keypoints.
TEST(FrameFeaturesRestored, KeepTheGivenPositionsAndRefuseAWrongCount) {
  const FrameFeatures seen = ThreeRowsAndOneWithoutDepth();
  const FrameFeatures moved = seen.AtMiddleRow({0.0, 2.0, 0.0}, Eigen::Vector3d::Zero(), kReadoutS);
  std::vector<cv::KeyPoint> keypoints;
  std::vector<double> depth, right_u;
  std::vector<Eigen::Vector2d> undistorted;
  for (int i = 0; i < moved.size(); ++i) {
    keypoints.push_back(moved.keypoint(i));
    depth.push_back(moved.depth(i));
    right_u.push_back(moved.right_u(i));
    undistorted.push_back(moved.undistorted(i));
  }
  const FrameFeatures restored(keypoints, moved.descriptors(), depth, right_u,
                               testing::TestCamera(), undistorted);
  for (int i = 0; i < moved.size(); ++i) EXPECT_EQ(restored.undistorted(i), moved.undistorted(i));
  undistorted.pop_back();
  EXPECT_THROW(static_cast<void>(FrameFeatures(keypoints, moved.descriptors(), depth, right_u,
                                               testing::TestCamera(), undistorted)),
               Error);
}

}  // namespace
}  // namespace noctua::slam
