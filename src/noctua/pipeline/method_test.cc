#include "noctua/pipeline/method.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/dynamic/coco.h"
#include "noctua/edges/edge_detector.h"
#include "noctua/image/enhancement.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::pipeline {
namespace {

using ::testing::HasSubstr;

class MethodTest : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    frame_ =
        noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  }
  static cv::Mat frame_;
};
cv::Mat MethodTest::frame_;

TEST_P(MethodTest, RunsOnARealFrameAndHonoursTheExclusionMask) {
  auto method = CreateMethod(GetParam(), MethodConfig{});
  EXPECT_EQ(method->name(), GetParam());
  const auto all = method->Run(frame_);
  ASSERT_GT(all.keypoints.size(), 100u);
  EXPECT_EQ(all.descriptors.rows, static_cast<int>(all.keypoints.size()));
  EXPECT_EQ(all.stats.final_count, static_cast<int>(all.keypoints.size()));
  // Binary descriptors are compared by Hamming distance; SIFT's and SURF's float ones by L2.
  const bool float_descriptors = GetParam() == "sift" || GetParam() == "surf";
  EXPECT_EQ(method->norm_type(), float_descriptors ? cv::NORM_L2 : cv::NORM_HAMMING);
  EXPECT_EQ(all.descriptors.type(), float_descriptors ? CV_32F : CV_8U);
  EXPECT_FALSE(method->feature2d().empty());

  cv::Mat exclusion(frame_.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect excluded(0, 0, frame_.cols / 2, frame_.rows);
  exclusion(excluded).setTo(255);
  const auto masked = method->Run(frame_, exclusion);
  ASSERT_GT(masked.keypoints.size(), 20u);
  for (const auto& point : masked.keypoints) {
    EXPECT_FALSE(excluded.contains(cv::Point(cvRound(point.pt.x), cvRound(point.pt.y))))
        << point.pt;
  }
  EXPECT_THROW(method->Run(frame_, cv::Mat(10, 10, CV_8UC1, cv::Scalar(0))), Error);
}

// Prepare pays the first frame's one-time costs and nothing else: the frames after it get what
// they get without it, including frames of another size.
TEST_P(MethodTest, PreparingChangesNoResult) {
  const auto fresh = CreateMethod(GetParam(), MethodConfig{})->Run(frame_);
  auto prepared = CreateMethod(GetParam(), MethodConfig{});
  prepared->Prepare(frame_.size());
  const auto after = prepared->Run(frame_);
  ASSERT_EQ(after.keypoints.size(), fresh.keypoints.size());
  const int norm = prepared->norm_type() == cv::NORM_HAMMING ? cv::NORM_HAMMING : cv::NORM_L2;
  EXPECT_EQ(cv::norm(after.descriptors, fresh.descriptors, norm), 0.0);
  auto wrong_size = CreateMethod(GetParam(), MethodConfig{});
  wrong_size->Prepare(cv::Size(320, 240));
  EXPECT_EQ(cv::norm(wrong_size->Run(frame_).descriptors, fresh.descriptors, norm), 0.0);
}

INSTANTIATE_TEST_SUITE_P(AllMethods, MethodTest, ::testing::ValuesIn(MethodNames()),
                         [](const auto& param_info) {
                           std::string name = param_info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(CreateMethod, UnknownNamesAreRefusedWithTheKnownOnes) {
  try {
    CreateMethod("akaze", MethodConfig{});
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("unknown method 'akaze'"));
    EXPECT_THAT(error.what(), HasSubstr("clahe-orb"));
  }
}

TEST(OptionsForMethod, SwitchesTheStagesOfEachBaseline) {
  const features::ExtractorOptions base;
  EXPECT_EQ(OptionsForMethod("orb", base).enhancement.method, image::EnhancementMethod::kNone);
  EXPECT_EQ(OptionsForMethod("he-orb", base).enhancement.method,
            image::EnhancementMethod::kHistogramEqualization);
  const auto clahe = OptionsForMethod("clahe-orb", base);
  EXPECT_EQ(clahe.enhancement.method, image::EnhancementMethod::kClahe);
  EXPECT_FALSE(clahe.edge_filter.enabled || clahe.nms_filter.enabled ||
               clahe.dynamic_filter.enabled);
  const auto paper = OptionsForMethod("paper", base);
  EXPECT_TRUE(paper.edge_filter.enabled && paper.nms_filter.enabled &&
              paper.dynamic_filter.enabled);
  EXPECT_THROW(OptionsForMethod("orb-opencv", base), Error);
}

TEST(CreateMethod, PaperKeepsOnlyPointsNearPhaseCongruencyEdges) {
  const cv::Mat frame =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1)[0], cv::IMREAD_COLOR);
  const MethodConfig config;
  const auto result = CreateMethod("paper", config)->Run(frame);
  ASSERT_GT(result.keypoints.size(), 50u);
  EXPECT_THAT(::testing::PrintToString(result.stats.stages_ran), HasSubstr("edge-filter"));
  EXPECT_LT(result.stats.after_edge, result.stats.after_dynamic);

  // The same edge map, made independently: the fast PC map of the CLAHE-enhanced frame.
  const features::ExtractorOptions options = OptionsForMethod("paper", config.extractor);
  const cv::Mat enhanced = image::Enhancer(options.enhancement).Apply(image::ToGray8U(frame));
  const cv::Mat edge_map =
      edges::CreateEdgeDetector(edges::EdgeDetectorOptions())->Detect(enhanced);
  cv::Mat distance;
  cv::distanceTransform(edge_map == 0, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  for (const cv::KeyPoint& point : result.keypoints) {
    const double scale = std::pow(options.fast.scale_factor, point.octave);
    const cv::Point pixel(std::clamp(cvRound(point.pt.x), 0, frame.cols - 1),
                          std::clamp(cvRound(point.pt.y), 0, frame.rows - 1));
    // Within the level's radius of a PC edge pixel, plus a pixel for rounding between levels.
    EXPECT_LE(distance.at<float>(pixel), options.edge_filter.radius_px * scale + 1.5)
        << "point " << point.pt << " octave " << point.octave;
  }
}

std::filesystem::path YoloV8n() {
  return noctua::testing::ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx";
}

TEST(CreateMethod, PaperWithADetectorLeavesNoPointOnThePeopleOfFr3Walking) {
  MethodConfig config;
  config.detector_model = YoloV8n().string();
  auto paper = CreateMethod("paper", config);
  // The people as a second, finer model sees them: the two largest person instance masks of
  // YOLOv8n-seg at full resolution.
  dynamic::DetectorOptions fine;
  fine.input_width = 640;
  fine.input_height = 480;
  const auto seg = dynamic::LoadDetector(
      noctua::testing::ModelsDir() / "yolov8n-seg" / "yolov8n-seg_head_f32.onnx", fine);
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(
           noctua::testing::DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb")) {
    paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  ASSERT_EQ(paths.size(), 16u);
  for (size_t i = 0; i < paths.size(); i += 7) {
    SCOPED_TRACE(paths[i].filename().string());
    const cv::Mat frame = noctua::testing::ReadImageOrThrow(paths[i], cv::IMREAD_COLOR);
    std::vector<cv::Mat> masks;
    for (const auto& d : seg->Detect(frame)) {
      if (d.class_id == dynamic::CocoClassId("person")) masks.push_back(d.mask);
    }
    ASSERT_GE(masks.size(), 2u);
    std::sort(masks.begin(), masks.end(), [](const cv::Mat& a, const cv::Mat& b) {
      return cv::countNonZero(a) > cv::countNonZero(b);
    });
    const cv::Mat people = masks[0] | masks[1];
    const auto result = paper->Run(frame);
    EXPECT_THAT(::testing::PrintToString(result.stats.stages_ran), HasSubstr("dynamic"));
    EXPECT_LT(result.stats.after_dynamic, result.stats.after_mask);
    int on_people = 0;
    for (const cv::KeyPoint& point : result.keypoints) {
      on_people += people.at<uchar>(cvRound(point.pt.y), cvRound(point.pt.x)) > 0;
    }
    EXPECT_EQ(on_people, 0);
    EXPECT_GT(result.keypoints.size(), 100u);
    // Without the detector, the same method keeps points on the people.
    int unfiltered_on_people = 0;
    for (const cv::KeyPoint& point : CreateMethod("paper", MethodConfig{})->Run(frame).keypoints) {
      unfiltered_on_people += people.at<uchar>(cvRound(point.pt.y), cvRound(point.pt.x)) > 0;
    }
    EXPECT_GT(unfiltered_on_people, 20);
  }
}

// The first `count` frames of the fr3 walking_rpy sample (16 in all), in time order.
std::vector<cv::Mat> Fr3WalkingFrames(std::size_t count) {
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(
           noctua::testing::DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb")) {
    paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  EXPECT_GE(paths.size(), count);
  std::vector<cv::Mat> frames;
  for (std::size_t i = 0; i < std::min(count, paths.size()); ++i) {
    frames.push_back(noctua::testing::ReadImageOrThrow(paths[i], cv::IMREAD_COLOR));
  }
  return frames;
}

// Detection ahead on its own thread gives, with every frame detected, exactly the points of
// detection in line; with every 3rd frame detected, the frames between carry the last mask.
TEST(CreateMethod, PaperDetectingAheadMatchesInlineDetectionAndNeedsSubmittedFrames) {
  const std::vector<cv::Mat> frames = Fr3WalkingFrames(4);
  MethodConfig config;
  config.detector_model = YoloV8n().string();
  auto inline_paper = CreateMethod("paper", config);
  EXPECT_EQ(inline_paper->detection_ahead(), nullptr);
  config.detect_ahead = true;
  config.detect_ahead_options.every_n = 1;
  auto ahead_paper = CreateMethod("paper", config);
  const auto masks = ahead_paper->detection_ahead();
  ASSERT_NE(masks, nullptr);
  for (const cv::Mat& frame : frames) masks->Submit(frame);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    SCOPED_TRACE(i);
    const auto expected = inline_paper->Run(frames[i]);
    const auto actual = ahead_paper->Run(frames[i]);
    EXPECT_LT(actual.stats.after_dynamic, actual.stats.after_mask);
    ASSERT_EQ(actual.keypoints.size(), expected.keypoints.size());
    EXPECT_EQ(cv::norm(actual.descriptors, expected.descriptors, cv::NORM_HAMMING), 0.0);
  }
  // Nothing submitted for this frame: a clear error, not a hang or a frame without its mask.
  EXPECT_THAT([&] { ahead_paper->Run(frames[0]); },
              ::testing::ThrowsMessage<Error>(HasSubstr("without a submitted frame")));

  // Every 3rd frame: frame 1 carries frame 0's mask (the people have moved a little).
  config.detect_ahead_options.every_n = 3;
  auto sparse_paper = CreateMethod("paper", config);
  for (const cv::Mat& frame : frames) sparse_paper->detection_ahead()->Submit(frame);
  const auto first = sparse_paper->Run(frames[0]);
  EXPECT_EQ(cv::norm(first.descriptors, inline_paper->Run(frames[0]).descriptors, cv::NORM_HAMMING),
            0.0);
  const auto carried = sparse_paper->Run(frames[1]);
  EXPECT_LT(carried.stats.after_dynamic, carried.stats.after_mask);
}

// On the real walking people of fr3, a mask carried to the next frames lags behind them; growing
// it with its age keeps the points of the carried frames off the people as detected in those
// frames (the reference: detection on every frame).
TEST(CreateMethod, GrowingCarriedMasksKeepsPointsOffThePeopleAsTheyMove) {
  const std::vector<cv::Mat> frames = Fr3WalkingFrames(16);
  MethodConfig config;
  config.detector_model = YoloV8n().string();
  const auto detector = dynamic::LoadDetector(config.detector_model, config.detector);
  std::vector<cv::Mat> people;  // each frame's own mask
  for (const cv::Mat& frame : frames) {
    people.push_back(dynamic::BuildDynamicMask(detector->Detect(frame), config.motion_levels,
                                               config.dynamic_mask, frame.size()));
  }
  const auto points_on_people = [&](int growth) {
    config.detect_ahead = true;
    config.detect_ahead_options.every_n = 3;
    config.detect_ahead_options.carried_growth_px = growth;
    auto paper = CreateMethod("paper", config);
    for (const cv::Mat& frame : frames) paper->detection_ahead()->Submit(frame);
    int on_people = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      for (const cv::KeyPoint& point : paper->Run(frames[i]).keypoints) {
        on_people += people[i].at<uchar>(cvRound(point.pt.y), cvRound(point.pt.x)) > 0;
      }
    }
    return on_people;
  };
  const int fixed = points_on_people(0);
  const int half = points_on_people(10);
  const int grown = points_on_people(dynamic::AsyncMaskOptions().carried_growth_px);
  std::printf(
      "points on the people, every 3rd frame detected: growth 0 px %d, 10 px/frame %d, "
      "default %d\n",
      fixed, half, grown);
  EXPECT_GT(fixed, 0);
  EXPECT_LT(half, fixed);
  EXPECT_LT(grown, half);
}

// The dynamic stage belongs to every method: with a detector, none keeps a point in the regions
// the detector marks on a real fr3 walking frame (the same detector's mask, built here), and
// without one each keeps points there. Detection ahead gives the same points as in line.
TEST(CreateMethod, EveryMethodTakesTheDetectorsDynamicRegions) {
  const std::vector<cv::Mat> frames = Fr3WalkingFrames(1);
  ASSERT_EQ(frames.size(), 1u);
  const cv::Mat& frame = frames[0];
  MethodConfig config;
  config.detector_model = YoloV8n().string();
  const auto detector = dynamic::LoadDetector(config.detector_model, config.detector);
  const cv::Mat dynamic = dynamic::BuildDynamicMask(detector->Detect(frame), config.motion_levels,
                                                    config.dynamic_mask, frame.size());
  ASSERT_GT(cv::countNonZero(dynamic), frame.total() / 10);
  const auto inside = [&](const std::vector<cv::KeyPoint>& points) {
    int count = 0;
    for (const cv::KeyPoint& point : points) {
      const int x = std::clamp(cvRound(point.pt.x), 0, frame.cols - 1);
      const int y = std::clamp(cvRound(point.pt.y), 0, frame.rows - 1);
      count += dynamic.at<uchar>(y, x) > 0;
    }
    return count;
  };
  for (const std::string& name : MethodNames()) {
    SCOPED_TRACE(name);
    const auto with = CreateMethod(name, config)->Run(frame);
    const auto without = CreateMethod(name, MethodConfig{})->Run(frame);
    EXPECT_GT(inside(without.keypoints), 20);
    EXPECT_EQ(inside(with.keypoints), 0);
    EXPECT_GT(with.keypoints.size(), 50u);
    EXPECT_EQ(with.descriptors.rows, static_cast<int>(with.keypoints.size()));
    // The same through the method's plain cv::Feature2D, the way the SLAM calls it; the regions
    // it left out are then the SLAM's to take, once (slam::RgbdSlam::SetDynamicRegions).
    std::vector<cv::KeyPoint> points;
    cv::Mat descriptors;
    const auto plain = CreateMethod(name, config);
    const auto latest_regions = plain->latest_dynamic_regions();
    EXPECT_TRUE(latest_regions().empty());
    plain->feature2d()->detectAndCompute(frame, cv::noArray(), points, descriptors);
    EXPECT_EQ(inside(points), 0);
    EXPECT_EQ(points.size(), with.keypoints.size());
    const cv::Mat taken = latest_regions();
    ASSERT_EQ(taken.size(), dynamic.size());
    EXPECT_EQ(cv::countNonZero(taken != dynamic), 0);
    EXPECT_TRUE(latest_regions().empty());
    EXPECT_TRUE(plain->used_masks()->TakeLatest().empty());

    MethodConfig ahead = config;
    ahead.detect_ahead = true;
    ahead.detect_ahead_options.every_n = 1;
    auto method = CreateMethod(name, ahead);
    ASSERT_NE(method->detection_ahead(), nullptr);
    // Preparing runs no detection and takes no mask: the submitted frame still gets its own.
    method->Prepare(frame.size());
    EXPECT_EQ(method->detection_ahead()->detections(), 0);
    method->detection_ahead()->Submit(frame);
    const auto detected_ahead = method->Run(frame);
    ASSERT_EQ(detected_ahead.keypoints.size(), with.keypoints.size());
    EXPECT_EQ(cv::norm(detected_ahead.descriptors, with.descriptors,
                       method->norm_type() == cv::NORM_HAMMING ? cv::NORM_HAMMING : cv::NORM_L2),
              0.0);
  }
}

TEST(CreateMethod, PaperWithABadDetectorPathNamesTheFile) {
  MethodConfig config;
  config.detector_model = "/nonexistent/detector.onnx";
  try {
    CreateMethod("paper", config);
    FAIL() << "a missing detector model was accepted";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("/nonexistent/detector.onnx"));
  }
}

}  // namespace
}  // namespace noctua::pipeline
