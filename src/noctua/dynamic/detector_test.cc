#include "noctua/dynamic/detector.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgproc.hpp>

#include "noctua/dynamic/coco.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

using noctua::testing::ModelsDir;
using noctua::testing::ReadImageOrThrow;

std::filesystem::path YoloV8n() { return ModelsDir() / "yolov8n" / "yolov8n_head_f32.onnx"; }
std::filesystem::path YoloV8nSeg() {
  return ModelsDir() / "yolov8n-seg" / "yolov8n-seg_head_f32.onnx";
}
std::filesystem::path YoloXNano() { return ModelsDir() / "yolox_nano" / "yolox_nano.onnx"; }
cv::Mat Image(const std::string& name) {
  return ReadImageOrThrow(ModelsDir() / "images" / name, cv::IMREAD_COLOR);
}

DetectorOptions Input(int width, int height) {
  DetectorOptions options;
  options.input_width = width;
  options.input_height = height;
  return options;
}

std::vector<Detection> OfClass(const std::vector<Detection>& detections, const char* name) {
  std::vector<Detection> out;
  for (const auto& d : detections) {
    if (d.class_id == CocoClassId(name)) out.push_back(d);
  }
  return out;
}

std::string Describe(const std::vector<Detection>& detections) {
  std::string text;
  for (const auto& d : detections) {
    text += CocoClassName(d.class_id) + " " + std::to_string(d.score) + " [" +
            std::to_string(d.box.x) + "," + std::to_string(d.box.y) + "," +
            std::to_string(d.box.br().x) + "," + std::to_string(d.box.br().y) + "]\n";
  }
  return text;
}

// Best IoU of `expected` (x0, y0, x1, y1) with any of the detections.
float BestIoU(const std::vector<Detection>& detections, cv::Rect2f expected) {
  float best = 0.0f;
  for (const auto& d : detections) best = std::max(best, IoU(d.box, expected));
  return best;
}
cv::Rect2f Corners(float x0, float y0, float x1, float y1) { return {x0, y0, x1 - x0, y1 - y0}; }

// Ultralytics' published result for bus.jpg (yolov8n, 640): four people and the bus.
const std::vector<cv::Rect2f>& BusPeople() {
  static const std::vector<cv::Rect2f> people = {
      Corners(671, 374, 810, 876), Corners(51, 398, 243, 904), Corners(221, 408, 343, 857),
      Corners(0, 550, 77, 872)};
  return people;
}
const cv::Rect2f kBus = Corners(32, 231, 798, 770);

// Models are loaded once for the suite: loading runs a forward pass.
class DetectorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // 480x640 holds bus.jpg (810x1080) exactly, as Ultralytics' 640 rectangular inference does.
    yolov8n_bus_ = LoadDetector(YoloV8n(), Input(480, 640)).release();
    seg_bus_ = LoadDetector(YoloV8nSeg(), Input(480, 640)).release();
    yolox_bus_ = LoadDetector(YoloXNano(), Input(480, 640)).release();
  }
  static void TearDownTestSuite() {
    delete yolov8n_bus_;
    delete seg_bus_;
    delete yolox_bus_;
  }
  static Detector* yolov8n_bus_;
  static Detector* seg_bus_;
  static Detector* yolox_bus_;
};
Detector* DetectorTest::yolov8n_bus_ = nullptr;
Detector* DetectorTest::seg_bus_ = nullptr;
Detector* DetectorTest::yolox_bus_ = nullptr;

TEST_F(DetectorTest, RecognisesEachModelFromItsOutputs) {
  EXPECT_EQ(yolov8n_bus_->kind(), ModelKind::kYoloV8Head);
  EXPECT_FALSE(yolov8n_bus_->has_masks());
  EXPECT_EQ(seg_bus_->kind(), ModelKind::kYoloV8SegHead);
  EXPECT_TRUE(seg_bus_->has_masks());
  EXPECT_EQ(yolox_bus_->kind(), ModelKind::kYoloX);
}

TEST_F(DetectorTest, YoloV8nFindsTheBusAndItsPassengersWhereUltralyticsDoes) {
  const auto detections = yolov8n_bus_->Detect(Image("bus.jpg"));
  SCOPED_TRACE(Describe(detections));
  const auto people = OfClass(detections, "person");
  EXPECT_EQ(people.size(), 4u);
  for (const auto& expected : BusPeople()) EXPECT_GE(BestIoU(people, expected), 0.8f);
  EXPECT_GE(BestIoU(OfClass(detections, "bus"), kBus), 0.8f);
  for (const auto& d : detections) EXPECT_TRUE(d.mask.empty());
}

TEST_F(DetectorTest, YoloV8nFindsBothPeopleInZidane) {
  const auto detector = LoadDetector(YoloV8n(), Input(640, 384));
  const auto detections = detector->Detect(Image("zidane.jpg"));
  SCOPED_TRACE(Describe(detections));
  const auto people = OfClass(detections, "person");
  ASSERT_EQ(people.size(), 2u);
  // Published: [747,41,1141,712] and [144,200,1109,711]... the second is the man on the left.
  EXPECT_GE(BestIoU(people, Corners(747, 41, 1141, 712)), 0.8f);
}

TEST_F(DetectorTest, GreyAndBgraImagesWork) {
  cv::Mat gray, bgra;
  cv::cvtColor(Image("bus.jpg"), gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(Image("bus.jpg"), bgra, cv::COLOR_BGR2BGRA);
  EXPECT_GE(OfClass(yolov8n_bus_->Detect(gray), "person").size(), 3u);
  EXPECT_EQ(OfClass(yolov8n_bus_->Detect(bgra), "person").size(), 4u);
  EXPECT_THROW(yolov8n_bus_->Detect(cv::Mat()), Error);
  EXPECT_THROW(yolov8n_bus_->Detect(cv::Mat(10, 10, CV_16UC1)), Error);
}

TEST_F(DetectorTest, YoloXNanoFindsThePeople) {
  const auto detections = yolox_bus_->Detect(Image("bus.jpg"));
  SCOPED_TRACE(Describe(detections));
  const auto people = OfClass(detections, "person");
  // The nano YOLOX misses the man cut by the left border; the three whole people it finds.
  EXPECT_GE(people.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_GE(BestIoU(people, BusPeople()[i]), 0.8f);
}

TEST_F(DetectorTest, YoloV8nSegMasksCoverThePeople) {
  const cv::Mat bus = Image("bus.jpg");
  const auto detections = seg_bus_->Detect(bus);
  SCOPED_TRACE(Describe(detections));
  const auto people = OfClass(detections, "person");
  EXPECT_GE(people.size(), 4u);
  for (const auto& expected : BusPeople()) EXPECT_GE(BestIoU(people, expected), 0.75f);
  for (const auto& person : people) {
    ASSERT_EQ(person.mask.size(), bus.size());
    ASSERT_EQ(person.mask.type(), CV_8U);
    const double area = cv::countNonZero(person.mask);
    // A standing person fills part of the box, never all of it nor a sliver.
    EXPECT_GT(area, 0.3 * person.box.area());
    EXPECT_LT(area, 0.95 * person.box.area());
    // The mask is one blob around the box's centre column.
    const cv::Moments m = cv::moments(person.mask, true);
    const cv::Point2f centroid(static_cast<float>(m.m10 / m.m00),
                               static_cast<float>(m.m01 / m.m00));
    EXPECT_TRUE(person.box.contains(centroid));
    cv::Mat outside = person.mask.clone();
    cv::rectangle(outside, person.box, cv::Scalar(0), cv::FILLED);
    EXPECT_LT(cv::countNonZero(outside), 0.05 * area);
  }
}

// --- Bad model files -------------------------------------------------------------------------

// Minimal protobuf writer: enough of ONNX's ModelProto to build a valid one-node model.
std::string Varint(uint64_t v) {
  std::string out;
  while (v >= 0x80) {
    out += static_cast<char>((v & 0x7f) | 0x80);
    v >>= 7;
  }
  out += static_cast<char>(v);
  return out;
}
std::string Bytes(int field, const std::string& payload) {
  return Varint(static_cast<uint64_t>(field) << 3 | 2) + Varint(payload.size()) + payload;
}
std::string Int(int field, uint64_t value) {
  return Varint(static_cast<uint64_t>(field) << 3) + Varint(value);
}
std::string TensorValue(const std::string& name, std::vector<int> shape) {
  std::string dims;
  for (int d : shape) dims += Bytes(1, Int(1, static_cast<uint64_t>(d)));
  const std::string tensor_type = Int(1, 1 /*FLOAT*/) + Bytes(2, dims);
  return Bytes(1, name) + Bytes(2, Bytes(1, tensor_type));
}
// images [1,3,64,64] -> Relu -> out: a real ONNX model whose output is no detector's.
std::string ReluModel() {
  const std::string node =
      Bytes(1, "images") + Bytes(2, "out") + Bytes(3, "relu") + Bytes(4, "Relu");
  const std::string graph = Bytes(1, node) + Bytes(2, "g") +
                            Bytes(11, TensorValue("images", {1, 3, 64, 64})) +
                            Bytes(12, TensorValue("out", {1, 3, 64, 64}));
  return Int(1, 7) + Bytes(7, graph) + Bytes(8, Bytes(1, "") + Int(2, 13));
}

std::string LoadError(const std::filesystem::path& path, const DetectorOptions& options = {}) {
  try {
    LoadDetector(path, options);
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(LoadDetector, MissingFileIsNamed) {
  const auto message = LoadError("/nonexistent/yolo.onnx");
  EXPECT_THAT(message, ::testing::HasSubstr("/nonexistent/yolo.onnx"));
  EXPECT_THAT(message, ::testing::HasSubstr("not found"));
}

TEST(LoadDetector, NonOnnxFileIsNamed) {
  const auto path = std::filesystem::path(::testing::TempDir()) / "not_a_model.onnx";
  std::ofstream(path) << "this is a text file, not a network\n";
  const auto message = LoadError(path);
  EXPECT_THAT(message, ::testing::HasSubstr(path.string()));
  EXPECT_THAT(message, ::testing::HasSubstr("not an ONNX model"));
  EXPECT_THAT(LoadError(ModelsDir() / "images"), ::testing::HasSubstr("not a file"));
}

TEST(LoadDetector, UnexpectedOutputsAreDescribed) {
  const auto path = std::filesystem::path(::testing::TempDir()) / "relu.onnx";
  std::ofstream(path, std::ios::binary) << ReluModel();
  const auto message = LoadError(path, Input(64, 64));
  EXPECT_THAT(message, ::testing::HasSubstr(path.string()));
  EXPECT_THAT(message, ::testing::HasSubstr("unexpected outputs [1, 3, 64, 64]"));
}

TEST(LoadDetector, BadOptionsAreRefusedBeforeLoading) {
  EXPECT_THAT(LoadError(YoloV8n(), Input(300, 256)), ::testing::HasSubstr("multiple of 32"));
  DetectorOptions options;
  options.score_threshold = 1.5f;
  EXPECT_THAT(LoadError(YoloV8n(), options), ::testing::HasSubstr("score_threshold"));
}

}  // namespace
}  // namespace noctua::dynamic
