#include "noctua/features/extractor.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/features/ofast.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::features {
namespace {

using ::testing::HasSubstr;

// The extractor with every stage of the paper off: ORB-SLAM's ORB.
ExtractorOptions OrbOptions() {
  ExtractorOptions options;
  options.enhancement.method = image::EnhancementMethod::kNone;
  options.dynamic_filter.enabled = false;
  options.edge_filter.enabled = false;
  options.nms_filter.enabled = false;
  return options;
}

ExtractorOptions ClaheOrbOptions() {
  ExtractorOptions options = OrbOptions();
  options.enhancement.method = image::EnhancementMethod::kClahe;
  return options;
}

cv::Ptr<cv::ORB> OpenCvOrb() {
  return cv::ORB::create(1000, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
}

class ExtractorOnFr1 : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (const auto& path : noctua::testing::Fr1RgbPaths(6)) {
      frames_.push_back(noctua::testing::ReadImageOrThrow(path, cv::IMREAD_COLOR));
    }
  }
  static std::vector<cv::Mat> frames_;
};
std::vector<cv::Mat> ExtractorOnFr1::frames_;

TEST_F(ExtractorOnFr1, KeypointsFollowOrbSlamSemantics) {
  Extractor extractor(OrbOptions());
  const Extraction result = extractor.Extract(frames_[0]);
  ASSERT_GT(result.keypoints.size(), 500u);
  ASSERT_EQ(result.descriptors.rows, static_cast<int>(result.keypoints.size()));
  EXPECT_EQ(result.descriptors.cols, 32);
  EXPECT_EQ(result.descriptors.type(), CV_8UC1);
  std::vector<int> per_level(8, 0);
  for (const auto& point : result.keypoints) {
    ASSERT_GE(point.octave, 0);
    ASSERT_LT(point.octave, 8);
    ++per_level[static_cast<std::size_t>(point.octave)];
    const double scale = std::pow(1.2, point.octave);
    EXPECT_NEAR(point.size, 31.0 * scale, 1e-3);
    // Level-0 coordinates keep the level's border, scaled.
    EXPECT_GE(point.pt.x, kEdgeThreshold * scale - 1e-3);
    EXPECT_GE(point.pt.y, kEdgeThreshold * scale - 1e-3);
    EXPECT_LT(point.pt.x, frames_[0].cols);
    EXPECT_LT(point.pt.y, frames_[0].rows);
    EXPECT_GE(point.angle, 0.0f);
    EXPECT_LT(point.angle, 360.0f);
    EXPECT_GT(point.response, 0.0f);
  }
  // Every level contributes, the finest most.
  for (int count : per_level) EXPECT_GT(count, 0);
  EXPECT_EQ(per_level[0], *std::max_element(per_level.begin(), per_level.end()));
}

TEST_F(ExtractorOnFr1, OrbModeCountIsWithinTenPercentOfOpenCvOrb) {
  // Same settings as OpenCV's ORB: one FAST threshold, no low-threshold fallback.
  ExtractorOptions options = OrbOptions();
  options.fast.min_fast_threshold = options.fast.initial_fast_threshold;
  Extractor ours(options);
  // ... and the same border: ORB-SLAM keeps points 19 px from each level's edge, OpenCV 31.
  auto theirs = cv::ORB::create(1000, 1.2f, 8, kEdgeThreshold, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  for (const auto& frame : frames_) {
    std::vector<cv::KeyPoint> reference;
    theirs->detect(frame, reference);
    const auto count = static_cast<double>(ours.Extract(frame).keypoints.size());
    EXPECT_NEAR(count, static_cast<double>(reference.size()),
                0.1 * static_cast<double>(reference.size()));
  }
}

int RatioTestMatches(const cv::Mat& a, const cv::Mat& b) {
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(a, b, knn, 2);
  return static_cast<int>(std::count_if(knn.begin(), knn.end(), [](const auto& pair) {
    return pair.size() == 2 && pair[0].distance < 0.8f * pair[1].distance;
  }));
}

TEST_F(ExtractorOnFr1, DescriptorsMatchConsecutiveFramesAsWellAsOpenCvOrb) {
  Extractor ours(OrbOptions());
  auto theirs = OpenCvOrb();
  int our_matches = 0;
  int their_matches = 0;
  for (std::size_t i = 0; i + 1 < frames_.size(); ++i) {
    our_matches += RatioTestMatches(ours.Extract(frames_[i]).descriptors,
                                    ours.Extract(frames_[i + 1]).descriptors);
    std::vector<cv::KeyPoint> ka, kb;
    cv::Mat da, db;
    theirs->detectAndCompute(frames_[i], cv::noArray(), ka, da);
    theirs->detectAndCompute(frames_[i + 1], cv::noArray(), kb, db);
    their_matches += RatioTestMatches(da, db);
  }
  EXPECT_GT(our_matches, 0.8 * their_matches);
}

TEST_F(ExtractorOnFr1, DescriptorsAreIdenticalToOpenCvOrbOnTheSamePoints) {
  auto theirs = OpenCvOrb();
  std::vector<cv::KeyPoint> points;
  cv::Mat reference;
  theirs->detectAndCompute(frames_[0], cv::noArray(), points, reference);
  // OpenCV orders its points by level too, so the order survives the recomputation.
  std::vector<cv::KeyPoint> ours_points = points;
  cv::Mat ours_descriptors;
  Extractor(OrbOptions())
      .detectAndCompute(frames_[0], cv::noArray(), ours_points, ours_descriptors, true);
  ASSERT_EQ(ours_points.size(), points.size());
  EXPECT_EQ(cv::norm(ours_descriptors, reference, cv::NORM_HAMMING), 0.0);
}

TEST_F(ExtractorOnFr1, ClaheOrbFindsSeveralTimesMoreThanOpenCvOrbOnDarkFrames) {
  Extractor clahe(ClaheOrbOptions());
  Extractor orb(OrbOptions());
  auto opencv = OpenCvOrb();
  double clahe_count = 0.0;
  double orb_count = 0.0;
  double opencv_count = 0.0;
  for (const auto& frame : frames_) {
    const cv::Mat dark = noctua::testing::ScaleBrightness(frame, 0.15);
    clahe_count += static_cast<double>(clahe.Extract(dark).keypoints.size());
    orb_count += static_cast<double>(orb.Extract(dark).keypoints.size());
    std::vector<cv::KeyPoint> points;
    opencv->detect(dark, points);
    opencv_count += static_cast<double>(points.size());
  }
  // OpenCV ORB (fixed FAST threshold 20) nearly goes blind; our ORB-SLAM-style grid falls back
  // to threshold 7 in empty cells and keeps some points, CLAHE restores most of them.
  EXPECT_GT(clahe_count, 3.0 * opencv_count);
  EXPECT_GT(clahe_count, 1.3 * orb_count);
}

TEST(Extractor, OrientationTurnsWithTheImage) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_GRAYSCALE);
  cv::Mat turned;
  cv::rotate(frame, turned, cv::ROTATE_90_CLOCKWISE);
  std::vector<cv::KeyPoint> points;
  cv::FAST(frame(cv::Rect(40, 40, frame.cols - 80, frame.rows - 80)), points, 20, true);
  ASSERT_GT(points.size(), 50u);
  for (auto& point : points) point.pt += cv::Point2f(40, 40);
  std::vector<cv::KeyPoint> moved = points;
  for (std::size_t i = 0; i < points.size(); ++i) {
    moved[i].pt = cv::Point2f(static_cast<float>(frame.rows - 1) - points[i].pt.y, points[i].pt.x);
  }
  ComputeOrientation(frame, points);
  ComputeOrientation(turned, moved);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double turn = std::fmod(moved[i].angle - points[i].angle + 720.0, 360.0);
    EXPECT_NEAR(turn, 90.0, 1.0) << "point " << i;
  }
}

TEST(Extractor, FiltersRemovePointsInTheDynamicMaskAndFarFromEdges) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  ExtractorOptions options;  // the paper's configuration
  options.edge_filter.radius_px = 2.0;
  Extractor extractor(options);

  cv::Mat dynamic(frame.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect person(200, 100, 180, 300);
  dynamic(person).setTo(255);
  cv::Mat edges(frame.size(), CV_8UC1, cv::Scalar(0));
  for (int x = 30; x < frame.cols; x += 40) cv::line(edges, {x, 0}, {x, frame.rows - 1}, 255);
  for (int y = 30; y < frame.rows; y += 40) cv::line(edges, {0, y}, {frame.cols - 1, y}, 255);

  const Extraction result = extractor.Extract(frame, dynamic, edges);
  ASSERT_GT(result.keypoints.size(), 50u);
  const cv::Mat distance = [&] {
    cv::Mat d;
    cv::distanceTransform(edges == 0, d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    return d;
  }();
  for (const auto& point : result.keypoints) {
    const cv::Point pixel(cvRound(point.pt.x), cvRound(point.pt.y));
    EXPECT_FALSE(person.contains(pixel)) << pixel;
    const double scale = std::pow(1.2, point.octave);
    EXPECT_LE(distance.at<float>(pixel), 2.0 * scale + 0.5) << pixel << " level " << point.octave;
  }
  const ExtractionStats& stats = result.stats;
  EXPECT_GE(stats.detected, stats.after_dynamic);
  EXPECT_GT(stats.after_mask, stats.after_dynamic);
  EXPECT_GT(stats.after_dynamic, stats.after_edge);
  EXPECT_GE(stats.after_edge, stats.after_nms);
  EXPECT_GE(stats.after_nms, stats.final_count);
  EXPECT_THAT(stats.stages_ran, ::testing::Contains("dynamic-filter"));
  EXPECT_THAT(stats.stages_ran, ::testing::Contains("edge-filter"));
}

// The fill is the strict filter's output plus points it dropped: where a sparse edge map leaves
// the levels short, it adds points up to what the frame offers without the edge filter, and keeps
// every strict point; with edges everywhere it changes nothing.
TEST(Extractor, EdgeFillTopsUpStarvedLevelsAndKeepsTheStrictPoints) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  ExtractorOptions strict_options;
  strict_options.dynamic_filter.enabled = false;
  ExtractorOptions fill_options = strict_options;
  fill_options.edge_filter.fill_to_quota = true;
  ExtractorOptions unfiltered_options = strict_options;
  unfiltered_options.edge_filter.enabled = false;
  Extractor strict(strict_options);
  Extractor fill(fill_options);

  // Lines 60 px apart leave most corners of the frame off the edges.
  cv::Mat sparse(frame.size(), CV_8UC1, cv::Scalar(0));
  for (int x = 30; x < frame.cols; x += 60) cv::line(sparse, {x, 0}, {x, frame.rows - 1}, 255);
  const Extraction strict_result = strict.Extract(frame, cv::Mat(), sparse);
  const Extraction fill_result = fill.Extract(frame, cv::Mat(), sparse);
  const int unfiltered = Extractor(unfiltered_options).Extract(frame).stats.final_count;
  const int quota = strict_options.fast.num_features;
  ASSERT_LT(strict_result.stats.final_count, unfiltered / 2);
  EXPECT_EQ(strict_result.stats.edge_fill, 0);
  EXPECT_GE(fill_result.stats.final_count, unfiltered * 95 / 100);
  EXPECT_LE(fill_result.stats.final_count, quota);
  EXPECT_EQ(fill_result.stats.edge_fill,
            fill_result.stats.final_count - strict_result.stats.final_count);
  EXPECT_EQ(fill_result.descriptors.rows, fill_result.stats.final_count);
  EXPECT_THAT(fill_result.stats.stages_ran, ::testing::Contains("edge-fill"));
  auto same = [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
    return a.pt == b.pt && a.octave == b.octave && a.angle == b.angle;
  };
  for (const auto& point : strict_result.keypoints) {
    EXPECT_TRUE(std::any_of(fill_result.keypoints.begin(), fill_result.keypoints.end(),
                            [&](const cv::KeyPoint& other) { return same(point, other); }))
        << point.pt << " level " << point.octave;
  }

  // Edges everywhere: the strict filter leaves every level its quota, and the fill adds nothing.
  const cv::Mat everywhere(frame.size(), CV_8UC1, cv::Scalar(255));
  const Extraction strict_full = strict.Extract(frame, cv::Mat(), everywhere);
  const Extraction fill_full = fill.Extract(frame, cv::Mat(), everywhere);
  EXPECT_EQ(fill_full.stats.edge_fill, 0);
  ASSERT_EQ(fill_full.keypoints.size(), strict_full.keypoints.size());
  for (std::size_t i = 0; i < fill_full.keypoints.size(); ++i) {
    EXPECT_TRUE(same(fill_full.keypoints[i], strict_full.keypoints[i])) << i;
  }
  EXPECT_EQ(cv::norm(fill_full.descriptors, strict_full.descriptors, cv::NORM_HAMMING), 0.0);
}

// The fill takes only what the edge filter dropped: points in the dynamic mask stay out.
TEST(Extractor, EdgeFillNeverBringsBackDynamicPoints) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  ExtractorOptions options;
  options.edge_filter.fill_to_quota = true;
  const cv::Rect person(200, 100, 180, 300);
  cv::Mat dynamic(frame.size(), CV_8UC1, cv::Scalar(0));
  dynamic(person).setTo(255);
  const cv::Mat no_edges(frame.size(), CV_8UC1, cv::Scalar(0));
  const Extraction result = Extractor(options).Extract(frame, dynamic, no_edges);
  ASSERT_GT(result.stats.edge_fill, 500);
  EXPECT_EQ(result.stats.after_edge, 0);
  for (const auto& point : result.keypoints) {
    EXPECT_FALSE(person.contains(cv::Point(cvRound(point.pt.x), cvRound(point.pt.y)))) << point.pt;
  }
}

TEST(Extractor, ReportsSkippedStagesWithoutMaps) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  Extractor extractor{ExtractorOptions{}};
  const Extraction result = extractor.Extract(frame);
  EXPECT_THAT(result.stats.stages_skipped,
              ::testing::Contains(HasSubstr("dynamic-filter (no dynamic mask")));
  EXPECT_THAT(result.stats.stages_skipped,
              ::testing::Contains(HasSubstr("edge-filter (no edge map")));
  EXPECT_EQ(result.stats.after_dynamic, result.stats.after_mask);
  EXPECT_GT(result.stats.stage_ms.at("fast"), 0.0);
}

TEST(Extractor, SourcesAreCalledWhenNoMapIsGiven) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  Extractor extractor{ExtractorOptions{}};
  int edge_calls = 0;
  int dynamic_calls = 0;
  extractor.SetEdgeMapSource([&](const cv::Mat& gray) {
    ++edge_calls;
    EXPECT_EQ(gray.type(), CV_8UC1);
    return cv::Mat(gray.size(), CV_8UC1, cv::Scalar(255));
  });
  extractor.SetDynamicMaskSource([&](const cv::Mat& image) {
    ++dynamic_calls;
    cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
    mask(cv::Rect(0, 0, image.cols / 2, image.rows)).setTo(255);
    return mask;
  });
  const Extraction result = extractor.Extract(frame);
  EXPECT_EQ(edge_calls, 1);
  EXPECT_EQ(dynamic_calls, 1);
  for (const auto& point : result.keypoints) EXPECT_GE(point.pt.x, frame.cols / 2 - 1);
}

TEST(Extractor, Feature2DMaskKeepsOnlyAllowedPixels) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  cv::Ptr<cv::Feature2D> feature2d = Extractor::Create(OrbOptions());
  cv::Mat allowed(frame.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect window(100, 100, 300, 200);
  allowed(window).setTo(255);
  std::vector<cv::KeyPoint> points;
  cv::Mat descriptors;
  feature2d->detectAndCompute(frame, allowed, points, descriptors);
  ASSERT_GT(points.size(), 20u);
  EXPECT_EQ(descriptors.rows, static_cast<int>(points.size()));
  for (const auto& point : points) {
    EXPECT_TRUE(window.contains(cv::Point(cvRound(point.pt.x), cvRound(point.pt.y))));
  }
  EXPECT_EQ(feature2d->descriptorSize(), 32);
  EXPECT_EQ(feature2d->defaultNorm(), cv::NORM_HAMMING);
}

TEST(Extractor, NoTwoSurvivorsShareAnNmsWindow) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  ExtractorOptions options = ClaheOrbOptions();
  options.nms_filter.enabled = true;
  options.nms_filter.window = 5;
  const Extraction result = Extractor(options).Extract(frame);
  ASSERT_GT(result.keypoints.size(), 100u);
  for (std::size_t i = 0; i < result.keypoints.size(); ++i) {
    for (std::size_t j = i + 1; j < result.keypoints.size(); ++j) {
      const auto& a = result.keypoints[i];
      const auto& b = result.keypoints[j];
      if (a.octave != b.octave) continue;
      const double scale = std::pow(1.2, a.octave);
      const double dx = std::abs(std::round(a.pt.x / scale) - std::round(b.pt.x / scale));
      const double dy = std::abs(std::round(a.pt.y / scale) - std::round(b.pt.y / scale));
      EXPECT_FALSE(dx <= 2 && dy <= 2) << a.pt << " and " << b.pt << " at level " << a.octave;
    }
  }
}

TEST(Extractor, ParallelAndSequentialRunsGiveIdenticalResults) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  ExtractorOptions options;
  options.parallel = false;
  Extractor sequential(options);
  options.parallel = true;
  Extractor parallel(options);
  cv::Mat edges(frame.size(), CV_8UC1, cv::Scalar(0));
  for (int x = 20; x < frame.cols; x += 25) edges.col(x).setTo(255);
  parallel.SetEdgeMapSource([&](const cv::Mat&) { return edges; });
  sequential.SetEdgeMapSource([&](const cv::Mat&) { return edges; });
  for (int run = 0; run < 3; ++run) {
    const Extraction a = sequential.Extract(frame);
    const Extraction b = parallel.Extract(frame);
    ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
    for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
      EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
      EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
      EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave);
    }
    EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);
    EXPECT_EQ(a.stats.after_edge, b.stats.after_edge);
  }
}

std::string ErrorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& error) {
    return error.what();
  }
  return "no error";
}

TEST(Extractor, BadInputGivesClearErrors) {
  Extractor extractor{ExtractorOptions{}};
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(cv::Mat()); }), HasSubstr("empty image"));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(cv::Mat(1, 1, CV_8UC1)); }),
              HasSubstr("smaller than"));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(cv::Mat(30, 300, CV_8UC1)); }),
              HasSubstr("smaller than"));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(cv::Mat(100, 100, CV_16UC1, cv::Scalar(0))); }),
              HasSubstr("8-bit"));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(cv::Mat(100, 100, CV_32FC1, cv::Scalar(0))); }),
              HasSubstr("8-bit"));
  const cv::Mat image(100, 120, CV_8UC1, cv::Scalar(0));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(image, cv::Mat(100, 100, CV_8UC1)); }),
              HasSubstr("dynamic mask is 100x100 but the image is 120x100"));
  EXPECT_THAT(ErrorOf([&] { extractor.Extract(image, cv::Mat(), cv::Mat(100, 120, CV_32FC1)); }),
              HasSubstr("edge map must be single-channel 8-bit"));
  std::vector<cv::KeyPoint> points;
  cv::Mat descriptors;
  EXPECT_THAT(ErrorOf([&] {
                extractor.detectAndCompute(image, cv::Mat(10, 10, CV_8UC1), points, descriptors);
              }),
              HasSubstr("mask is 10x10"));
}

TEST(Extractor, SmallestAcceptedAndFlatImagesGiveNoPointsWithoutFailing) {
  Extractor extractor{ExtractorOptions{}};
  const Extraction tiny = extractor.Extract(cv::Mat(39, 39, CV_8UC1, cv::Scalar(128)));
  EXPECT_TRUE(tiny.keypoints.empty());
  EXPECT_EQ(tiny.descriptors.rows, 0);
  const Extraction flat = extractor.Extract(cv::Mat(480, 640, CV_8UC3, cv::Scalar(50, 60, 70)));
  EXPECT_TRUE(flat.keypoints.empty());
}

}  // namespace
}  // namespace noctua::features
