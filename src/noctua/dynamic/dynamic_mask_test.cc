#include "noctua/dynamic/dynamic_mask.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <mutex>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "noctua/dynamic/async_masks.h"
#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/detection_overlay.h"
#include "noctua/geometry/camera.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

using noctua::testing::DataDir;
using noctua::testing::ModelsDir;

std::vector<cv::Mat> Fr3WalkingFrames() {
  std::vector<std::filesystem::path> paths;
  for (const auto& entry :
       std::filesystem::directory_iterator(DataDir() / "tum_fr3_walking_rpy_rgb16" / "rgb")) {
    paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  std::vector<cv::Mat> frames;
  for (const auto& path : paths) {
    frames.push_back(noctua::testing::ReadImageOrThrow(path, cv::IMREAD_COLOR));
  }
  return frames;
}

Detection Box(int class_id, float x, float y, float w, float h) {
  Detection detection;
  detection.box = {x, y, w, h};
  detection.class_id = class_id;
  detection.score = 0.9f;
  return detection;
}

// A generated RGB-D view with a known answer: a wall at 4 m, a "person" at 1.5 m standing in
// front of it, a patch without depth on the person, and the person's detection box reaching past
// them over the wall. Cut to depth, the region is the person and the unknown patch, not the wall.
TEST(DepthSegment, CutsABoxToThePersonsDepthAndFollowsACarriedPerson) {
  const cv::Size size(640, 480);
  const cv::Rect person(200, 100, 120, 370);
  const auto depth_with_person_at = [&](int dx) {
    cv::Mat depth(size, CV_32F, cv::Scalar(4.0f));
    depth(person + cv::Point(dx, 0)).setTo(1.5f);
    depth(cv::Rect(240 + dx, 200, 20, 20)).setTo(0.0f);  // no reading
    return depth;
  };
  const cv::Mat depth = depth_with_person_at(0);
  const std::vector<Detection> detections = {Box(0, 160, 60, 200, 420)};  // a person's box
  const MotionLevelTable table;
  DynamicMaskOptions options;
  options.dilation_px = 0;

  const cv::Mat boxes = BuildDynamicMask(detections, table, options, size);
  EXPECT_EQ(cv::countNonZero(boxes), 200 * 420);
  const auto objects = FindDynamicObjects(detections, table, options, size, depth);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_NEAR(objects[0].depth_m, 1.5, 1e-6);
  const cv::Mat cut = BuildDynamicMask(detections, table, options, size, depth);
  cv::Mat expected = cv::Mat::zeros(size, CV_8U);
  expected(person).setTo(255);
  EXPECT_EQ(cv::countNonZero(cut != expected), 0);

  // Two frames later the person has moved 15 px right; the box detected then, grown by 20 px,
  // cut to this frame's depth, covers the person where they are now and still no wall.
  const cv::Mat later = depth_with_person_at(15);
  const cv::Mat carried = DynamicObjectsMask(objects, options, size, later, 20);
  cv::Mat moved = cv::Mat::zeros(size, CV_8U);
  moved(person + cv::Point(15, 0)).setTo(255);
  EXPECT_EQ(cv::countNonZero(carried != moved), 0);

  // Off, or without depth, the box stays whole.
  options.depth_segment = false;
  EXPECT_EQ(cv::countNonZero(BuildDynamicMask(detections, table, options, size, depth)), 200 * 420);
  // The tolerance follows the sensor's noise: wider far away.
  EXPECT_GT(geometry::DepthNoiseSigma(4.0), 5 * geometry::DepthNoiseSigma(1.0));
}

TEST(LargestInstanceMask, PicksTheLargestMaskOfTheClassOnly) {
  const cv::Size size(64, 48);
  auto with_mask = [&](int class_id, cv::Rect region) {
    Detection detection = Box(class_id, region.x, region.y, region.width, region.height);
    detection.mask = cv::Mat::zeros(size, CV_8UC1);
    detection.mask(region).setTo(255);
    return detection;
  };
  const std::vector<Detection> detections = {
      with_mask(0, {0, 0, 10, 10}), with_mask(2, {0, 0, 40, 40}),  // a larger car
      with_mask(0, {20, 5, 12, 20}), Box(0, 0, 0, 60, 40)};        // a larger box, no mask
  const cv::Mat person = LargestInstanceMask(detections, CocoClassId("person"));
  ASSERT_FALSE(person.empty());
  EXPECT_EQ(cv::countNonZero(person), 12 * 20);
  EXPECT_EQ(cv::boundingRect(person), cv::Rect(20, 5, 12, 20));
  EXPECT_TRUE(LargestInstanceMask(detections, CocoClassId("dog")).empty());
  EXPECT_TRUE(LargestInstanceMask({Box(0, 0, 0, 10, 10)}, 0).empty());
}

TEST(BuildDynamicMask, OnlyDynamicLevelsWithBoxesInstancesAndDilation) {
  const int person = CocoClassId("person"), chair = CocoClassId("chair");
  const int car = CocoClassId("car");
  Detection with_mask = Box(person, 50, 50, 20, 20);
  with_mask.mask = cv::Mat::zeros(100, 100, CV_8U);
  cv::circle(with_mask.mask, {60, 60}, 5, cv::Scalar(255), cv::FILLED);
  const std::vector<Detection> detections = {Box(person, 10.4f, 10.4f, 10, 10),
                                             Box(chair, 80, 80, 10, 10), Box(car, 0, 80, 10, 10),
                                             with_mask};
  const MotionLevelTable table;
  DynamicMaskOptions options;
  options.dilation_px = 0;
  const cv::Mat high = BuildDynamicMask(detections, table, options, {100, 100});
  ASSERT_EQ(high.type(), CV_8U);
  ASSERT_EQ(high.size(), cv::Size(100, 100));
  // The box covers every pixel it touches: [10, 21) x [10, 21).
  EXPECT_EQ(cv::countNonZero(high(cv::Rect(10, 10, 11, 11))), 121);
  EXPECT_EQ(high.at<uchar>(85, 85), 0);  // chair: medium, not dynamic by default
  EXPECT_EQ(high.at<uchar>(85, 5), 0);   // car: static
  EXPECT_EQ(high.at<uchar>(60, 60), 255);
  EXPECT_EQ(high.at<uchar>(51, 51), 0);  // instance mask used, not its box
  EXPECT_EQ(cv::countNonZero(high), 121 + cv::countNonZero(with_mask.mask));

  options.shape = RegionShape::kBox;
  options.dynamic_levels = {MotionLevel::kHigh, MotionLevel::kMedium};
  const cv::Mat boxes = BuildDynamicMask(detections, table, options, {100, 100});
  EXPECT_EQ(boxes.at<uchar>(51, 51), 255);
  EXPECT_EQ(boxes.at<uchar>(85, 85), 255);
  EXPECT_EQ(boxes.at<uchar>(85, 5), 0);

  options.dilation_px = 3;
  const cv::Mat dilated = BuildDynamicMask(detections, table, options, {100, 100});
  EXPECT_EQ(dilated.at<uchar>(15, 7), 255);
  EXPECT_EQ(dilated.at<uchar>(15, 6), 0);
  options.dilation_px = -1;
  EXPECT_THROW(BuildDynamicMask(detections, table, options, {100, 100}), Error);
}

// One detector at the default input for the fr3 tests.
class Fr3Test : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    frames_ = new std::vector<cv::Mat>(Fr3WalkingFrames());
    detector_ = LoadDetector(ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx").release();
  }
  static void TearDownTestSuite() {
    delete frames_;
    delete detector_;
  }
  static std::vector<cv::Mat>* frames_;
  static Detector* detector_;
};
std::vector<cv::Mat>* Fr3Test::frames_ = nullptr;
Detector* Fr3Test::detector_ = nullptr;

TEST_F(Fr3Test, BothPeopleDetectedInEveryFrameAtTheDefaultInput) {
  ASSERT_EQ(frames_->size(), 16u);
  // Drawn by hand on the first frame: the man seated at the desk on the left and the man standing
  // in the middle.
  const cv::Rect2f seated(75, 178, 260, 302), standing(322, 0, 210, 480);
  for (size_t i = 0; i < frames_->size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    std::vector<Detection> people;
    for (const auto& d : detector_->Detect((*frames_)[i])) {
      if (d.class_id == CocoClassId("person")) people.push_back(d);
    }
    ASSERT_GE(people.size(), 2u);
    if (i == 0) {
      float best_seated = 0.0f, best_standing = 0.0f;
      for (const auto& p : people) {
        best_seated = std::max(best_seated, IoU(p.box, seated));
        best_standing = std::max(best_standing, IoU(p.box, standing));
      }
      EXPECT_GE(best_seated, 0.7f);
      EXPECT_GE(best_standing, 0.7f);
    }
  }
}

TEST_F(Fr3Test, AsyncMasksEqualSynchronousOnesAndCarryOver) {
  auto shared =
      std::shared_ptr<Detector>(LoadDetector(ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx"));
  const MotionLevelTable table;
  const DynamicMaskOptions options;
  const auto source = MakeDynamicMaskSource(shared, table, options);
  std::vector<cv::Mat> expected;
  for (size_t i = 0; i < 6; ++i) expected.push_back(source((*frames_)[i]));
  {
    AsyncMaskPipeline every(shared, table, options, AsyncMaskOptions{1});
    every.Submit((*frames_)[0]);
    for (size_t i = 0; i < 6; ++i) {
      if (i + 1 < 6) every.Submit((*frames_)[i + 1]);
      const cv::Mat mask = every.Next();
      EXPECT_EQ(cv::norm(mask, expected[i], cv::NORM_L1), 0.0) << "frame " << i;
    }
    EXPECT_EQ(every.outstanding(), 0);
    EXPECT_THROW(every.Next(), Error);
  }
  AsyncMaskPipeline third(shared, table, options, AsyncMaskOptions{3, 0});
  for (size_t i = 0; i < 6; ++i) third.Submit((*frames_)[i]);
  for (size_t i = 0; i < 6; ++i) {
    // Frames 0 and 3 are detected; 1, 2 and 4, 5 carry their masks over.
    EXPECT_EQ(cv::norm(third.Next(), expected[i - i % 3], cv::NORM_L1), 0.0) << "frame " << i;
  }
  // Carried masks grow by carried_growth_px per frame of age: a square of that half-width times
  // the age.
  AsyncMaskPipeline growing(shared, table, options, AsyncMaskOptions{3, 4});
  for (size_t i = 0; i < 6; ++i) growing.Submit((*frames_)[i]);
  for (size_t i = 0; i < 6; ++i) {
    const int age = static_cast<int>(i % 3);
    cv::Mat grown = expected[i - i % 3].clone();
    if (age > 0) {
      cv::dilate(
          grown, grown,
          cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * 4 * age + 1, 2 * 4 * age + 1)));
      EXPECT_GT(cv::countNonZero(grown), cv::countNonZero(expected[i - i % 3])) << "frame " << i;
    }
    EXPECT_EQ(cv::norm(growing.Next(), grown, cv::NORM_L1), 0.0) << "frame " << i;
  }
  EXPECT_THROW(AsyncMaskPipeline(shared, table, options, AsyncMaskOptions{0}), Error);
  EXPECT_THROW(AsyncMaskPipeline(shared, table, options, AsyncMaskOptions{3, -1}), Error);
}

TEST_F(Fr3Test, AsyncMasksPassOnDetectionErrors) {
  auto shared =
      std::shared_ptr<Detector>(LoadDetector(ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx"));
  AsyncMaskPipeline masks(shared, MotionLevelTable(), DynamicMaskOptions(), AsyncMaskOptions{1});
  masks.Submit(cv::Mat(8, 8, CV_16UC1, cv::Scalar(0)));
  masks.Submit((*frames_)[0]);
  EXPECT_THROW(masks.Next(), Error);
  EXPECT_GT(cv::countNonZero(masks.Next()), 0);
}

// Polls `done` for up to 10 s.
void WaitFor(const std::function<bool()>& done) {
  for (int waited_ms = 0; !done() && waited_ms < 10000; waited_ms += 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

// One person per frame, at x = 10 × the frame's grey value.
std::vector<Detection> PersonAt(const cv::Mat& image) {
  return {Box(CocoClassId("person"), 10.0f * image.at<uchar>(0, 0), 10.0f, 20.0f, 40.0f)};
}

// PersonAt, held inside Detect until the test allows the call: a detector slower than the frames.
class GatedDetector : public Detector {
 public:
  std::vector<Detection> Detect(const cv::Mat& image) override {
    std::unique_lock lock(mutex_);
    ++entered_;
    open_.wait(lock, [this] { return calls_ < allowed_; });
    ++calls_;
    return PersonAt(image);
  }
  void Allow(int calls) {
    std::lock_guard lock(mutex_);
    allowed_ = calls;
    open_.notify_all();
  }
  int entered() {
    std::lock_guard lock(mutex_);
    return entered_;
  }
  ModelKind kind() const override { return ModelKind::kYoloV8Head; }
  bool has_masks() const override { return false; }
  const DetectorOptions& options() const override { return options_; }

 private:
  std::mutex mutex_;
  std::condition_variable open_;
  int entered_ = 0;
  int calls_ = 0;
  int allowed_ = 0;
  DetectorOptions options_;
};

TEST(AsyncMasksWithoutWaiting, CarryTheNewestDetectionAndSkipFramesTheDetectorCannotTake) {
  auto detector = std::make_shared<GatedDetector>();
  const MotionLevelTable table;
  const DynamicMaskOptions options;
  constexpr int kGrowth = 2;
  AsyncMaskOptions async{1, kGrowth};
  async.wait_for_detection = false;
  AsyncMaskPipeline masks(detector, table, options, async);
  const cv::Size size(100, 80);
  const auto frame = [&](int k) { return cv::Mat(size, CV_8UC1, cv::Scalar(k)); };
  // Frame d's detection carried to frame k.
  const auto carried = [&](int d, int k) {
    const auto objects = FindDynamicObjects(PersonAt(frame(d)), table, options, size);
    return DynamicObjectsMask(objects, options, size, cv::Mat(), std::abs(k - d) * kGrowth);
  };
  const auto expect_mask = [&](int d, int k) {
    EXPECT_EQ(cv::norm(masks.Next(), carried(d, k), cv::NORM_L1), 0.0)
        << "frame " << k << " should carry frame " << d << "'s detection";
  };
  // Before the first detection finishes a frame does not wait: it has no dynamic region.
  masks.Submit(frame(0));
  WaitFor([&] { return detector->entered() == 1; });
  EXPECT_EQ(cv::countNonZero(masks.Next()), 0);
  EXPECT_TRUE(masks.TakeLateMasks().empty());  // nothing is known yet
  detector->Allow(1);
  WaitFor([&] { return masks.detections() == 1; });
  // Now it is: frame 0 gets the regions it would have carried, once.
  const auto late = masks.TakeLateMasks();
  ASSERT_EQ(late.size(), 1u);
  EXPECT_EQ(late[0].index, 0);
  EXPECT_EQ(cv::norm(late[0].mask, carried(0, 0), cv::NORM_L1), 0.0);
  EXPECT_GT(cv::countNonZero(late[0].mask), 0);
  EXPECT_TRUE(masks.TakeLateMasks().empty());
  // The detector is held on frame 1: frames 1-3 do not wait, they carry frame 0's detection.
  masks.Submit(frame(1));
  WaitFor([&] { return detector->entered() == 2; });
  masks.Submit(frame(2));
  masks.Submit(frame(3));
  for (int k = 1; k <= 3; ++k) expect_mask(0, k);
  EXPECT_EQ(masks.detections(), 1);
  // Let it go: it finishes frame 1, then takes the newest frame, 3, and leaves 2 out.
  detector->Allow(3);
  WaitFor([&] { return masks.detections() == 3; });
  ASSERT_EQ(masks.detections(), 3);
  masks.Submit(frame(4));  // held again
  expect_mask(3, 4);
  EXPECT_EQ(masks.outstanding(), 0);
  EXPECT_THROW(masks.Next(), Error);
  detector->Allow(100);  // the worker stops only between detections
}

TEST_F(Fr3Test, NoFeaturePointRemainsOnThePeopleAfterTheMask) {
  // The people as a second, finer model sees them: YOLOv8n-seg instance masks at full
  // resolution. The filter under test uses the default (YOLOv8n, 320x256, dilated boxes).
  DetectorOptions fine;
  fine.input_width = 640;
  fine.input_height = 480;
  const auto seg = LoadDetector(ModelsDir() / "yolov8n-seg" / "yolov8n-seg_head_f32.onnx", fine);
  const auto source = MakeDynamicMaskSource(
      std::shared_ptr<Detector>(LoadDetector(ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx")),
      MotionLevelTable(), DynamicMaskOptions{.shape = RegionShape::kBox});
  const auto orb = cv::ORB::create(1000);
  for (size_t i = 0; i < frames_->size(); i += 5) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const cv::Mat& frame = (*frames_)[i];
    // The scene's two people are the two largest person masks (the seg model also sees a sliver
    // of a third at the right border in some frames).
    std::vector<cv::Mat> masks;
    for (const auto& d : seg->Detect(frame)) {
      if (d.class_id == CocoClassId("person")) masks.push_back(d.mask);
    }
    ASSERT_GE(masks.size(), 2u);
    std::sort(masks.begin(), masks.end(), [](const cv::Mat& a, const cv::Mat& b) {
      return cv::countNonZero(a) > cv::countNonZero(b);
    });
    cv::Mat people = masks[0] | masks[1];
    ASSERT_GT(cv::countNonZero(people), frame.total() / 10);
    std::vector<cv::KeyPoint> all, kept;
    orb->detect(frame, all);
    orb->detect(frame, kept, source(frame) == 0);
    const auto on_people = [&](const std::vector<cv::KeyPoint>& points) {
      std::vector<cv::Point> found;
      for (const auto& p : points) {
        const cv::Point at(cvRound(p.pt.x), cvRound(p.pt.y));
        if (people.at<uchar>(at) > 0) found.push_back(at);
      }
      return found;
    };
    // The people are textured: unfiltered, many points lie on them.
    EXPECT_GT(on_people(all).size(), 50u);
    const auto left = on_people(kept);
    EXPECT_TRUE(left.empty()) << left.size() << " points left on people, first at " << left[0];
    EXPECT_GT(kept.size(), 300u);  // the rest of the scene keeps its points
  }
}

TEST(DetectionsJson, ReportsClassBoxLevelAndWhetherItIsDynamic) {
  const MotionLevelTable table;
  const DynamicMaskOptions options;  // high motion level only
  Detection person = Box(CocoClassId("person"), 10, 20, 30, 40);
  person.mask = cv::Mat::zeros(100, 100, CV_8UC1);
  person.mask(cv::Rect(10, 20, 5, 4)).setTo(255);
  const nlohmann::json json =
      DetectionsJson({person, Box(CocoClassId("chair"), 0, 0, 5, 5)}, table, options);
  ASSERT_EQ(json.size(), 2u);
  EXPECT_EQ(json[0]["class"], "person");
  EXPECT_EQ(json[0]["box"], nlohmann::json({10, 20, 40, 60}));
  EXPECT_EQ(json[0]["motion_level"], "high");
  EXPECT_TRUE(json[0]["dynamic"].get<bool>());
  EXPECT_EQ(json[0]["mask_area"], 20);
  EXPECT_FALSE(json[1]["dynamic"].get<bool>());
  EXPECT_FALSE(json[1].contains("mask_area"));
}

TEST(ParseInputSize, ReadsWidthByHeightAndNamesTheOptionOtherwise) {
  EXPECT_EQ(ParseInputSize("320x256", "--input"), cv::Size(320, 256));
  for (const char* bad : {"320", "320x", "320*256", "320x256x3", "x256"}) {
    try {
      ParseInputSize(bad, "--input");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("--input '" + std::string(bad) + "'"),
                std::string::npos);
    }
  }
}

}  // namespace
}  // namespace noctua::dynamic
