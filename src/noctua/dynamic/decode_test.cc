#include "noctua/dynamic/decode.h"

#include <gtest/gtest.h>

#include <cmath>

#include "noctua/dynamic/detection.h"
#include "noctua/dynamic/letterbox.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

cv::Mat Blob(std::vector<int> shape, float fill) {
  cv::Mat blob(static_cast<int>(shape.size()), shape.data(), CV_32F, cv::Scalar(fill));
  return blob;
}

float& At3(cv::Mat& blob, int row, int col) { return blob.ptr<float>()[row * blob.size[2] + col]; }

float& At4(cv::Mat& blob, int c, int y, int x) {
  return blob.ptr<float>()[(c * blob.size[2] + y) * blob.size[3] + x];
}

void ExpectBox(const cv::Rect2f& box, float x0, float y0, float x1, float y1) {
  EXPECT_NEAR(box.x, x0, 1e-3);
  EXPECT_NEAR(box.y, y0, 1e-3);
  EXPECT_NEAR(box.x + box.width, x1, 1e-3);
  EXPECT_NEAR(box.y + box.height, y1, 1e-3);
}

// A [1, 4 + 80 (+ extra), N] stock tensor with one object per listed anchor.
void PutStock(cv::Mat& out, int anchor, float cx, float cy, float w, float h, int cls,
              float score) {
  At3(out, 0, anchor) = cx;
  At3(out, 1, anchor) = cy;
  At3(out, 2, anchor) = w;
  At3(out, 3, anchor) = h;
  At3(out, 4 + cls, anchor) = score;
}

TEST(DecodeYoloV8Stock, FindsTheBoxesBuiltIntoTheTensor) {
  for (const int extra : {0, 32}) {  // detection and -seg exports
    cv::Mat out = Blob({1, 84 + extra, 12}, 0.0f);
    PutStock(out, 3, 100, 50, 40, 20, 0, 0.9f);
    PutStock(out, 7, 250, 230, 100, 60, 5, 0.8f);
    PutStock(out, 8, 252, 232, 100, 60, 5, 0.6f);  // same object, weaker: NMS removes it
    PutStock(out, 9, 250, 230, 100, 60, 2, 0.7f);  // same place, other class: kept
    PutStock(out, 1, 10, 10, 5, 5, 7, 0.1f);       // below the threshold
    for (int k = 0; k < extra; ++k) At3(out, 84 + k, 3) = 50.0f;  // coefficients, not scores
    const auto candidates = DecodeYoloV8Stock(out, 80, 0.25f);
    ASSERT_EQ(candidates.size(), 4u);
    const auto kept = PerClassNms(candidates, 0.45f, 100);
    ASSERT_EQ(kept.size(), 3u);
    EXPECT_EQ(kept[0].class_id, 0);
    EXPECT_EQ(kept[0].anchor, 3);
    EXPECT_FLOAT_EQ(kept[0].score, 0.9f);
    ExpectBox(kept[0].box, 80, 40, 120, 60);
    EXPECT_EQ(kept[1].class_id, 5);
    EXPECT_EQ(kept[1].anchor, 7);
    ExpectBox(kept[1].box, 200, 200, 300, 260);
    EXPECT_EQ(kept[2].class_id, 2);
    EXPECT_EQ(kept[2].anchor, 9);
  }
}

TEST(DecodeYoloV8Stock, RefusesATensorWithTooFewRows) {
  EXPECT_THROW(DecodeYoloV8Stock(Blob({1, 20, 5}, 0.0f), 80, 0.25f), Error);
  EXPECT_THROW(DecodeYoloV8Stock(Blob({1, 84}, 0.0f), 80, 0.25f), Error);
}

TEST(DecodeYoloV8Head, DflExpectationAnchorsAndStrides) {
  // Input 64x64: grids 8x8, 4x4, 2x2 for strides 8, 16, 32.
  std::vector<YoloV8HeadLevel> levels;
  for (const int s : {8, 16, 32}) {
    levels.push_back(
        {Blob({1, 64, 64 / s, 64 / s}, 0.0f), Blob({1, 80, 64 / s, 64 / s}, -10.0f), s});
  }
  // One object at stride 16, cell (gx 1, gy 2), class 3. Each side's distribution puts equal
  // weight on two neighbouring bins, so its expectation is their midpoint.
  YoloV8HeadLevel& level = levels[1];
  At4(level.class_map, 3, 2, 1) = 2.0f;
  const float expected_bins[4] = {1.5f, 1.0f, 2.0f, 0.5f};  // left, top, right, bottom
  for (int side = 0; side < 4; ++side) {
    for (int b = 0; b < 16; ++b) At4(level.box_map, side * 16 + b, 2, 1) = -100.0f;
    const int lo = static_cast<int>(std::floor(expected_bins[side]));
    const int hi = static_cast<int>(std::ceil(expected_bins[side]));
    At4(level.box_map, side * 16 + lo, 2, 1) = 10.0f;
    At4(level.box_map, side * 16 + hi, 2, 1) = 10.0f;
  }
  const auto candidates = DecodeYoloV8Head(levels, 0.25f);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates[0].class_id, 3);
  EXPECT_NEAR(candidates[0].score, 1.0f / (1.0f + std::exp(-2.0f)), 1e-6);
  EXPECT_EQ(candidates[0].anchor, 64 + 2 * 4 + 1);
  // anchor (1.5, 2.5); box = ((1.5-1.5), (2.5-1), (1.5+2), (2.5+0.5)) x 16.
  ExpectBox(candidates[0].box, 0, 24, 56, 48);
}

TEST(DecodeYoloV8Head, ScoreThresholdAppliesToTheSigmoid) {
  std::vector<YoloV8HeadLevel> levels = {
      {Blob({1, 64, 2, 2}, 0.0f), Blob({1, 80, 2, 2}, -10.0f), 32}};
  At4(levels[0].class_map, 0, 0, 0) = std::log(0.3f / 0.7f) + 0.01f;  // score just above 0.3
  At4(levels[0].class_map, 0, 1, 1) = std::log(0.3f / 0.7f) - 0.01f;  // just below
  const auto candidates = DecodeYoloV8Head(levels, 0.3f);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates[0].anchor, 0);
  // Uniform bins: each side at the mean index 7.5.
  ExpectBox(candidates[0].box, (0.5f - 7.5f) * 32, (0.5f - 7.5f) * 32, (0.5f + 7.5f) * 32,
            (0.5f + 7.5f) * 32);
}

TEST(DecodeYoloX, GridOffsetsExponentialSizesAndObjectness) {
  cv::Mat out = Blob({1, 64 + 16 + 4, 85}, 0.0f);
  const int row = 64 + 1 * 4 + 2;  // stride 16, cell (gx 2, gy 1)
  At3(out, row, 0) = 0.5f;
  At3(out, row, 1) = 0.25f;
  At3(out, row, 2) = std::log(2.0f);
  At3(out, row, 3) = std::log(1.5f);
  At3(out, row, 4) = 0.9f;
  At3(out, row, 5 + 7) = 0.8f;
  At3(out, 5, 4) = 0.9f;  // objectness without a class: score 0
  const auto candidates = DecodeYoloX(out, {64, 64}, 0.25f);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates[0].class_id, 7);
  EXPECT_NEAR(candidates[0].score, 0.72f, 1e-6);
  // centre ((0.5+2)*16, (0.25+1)*16) = (40, 20); size (32, 24).
  ExpectBox(candidates[0].box, 24, 8, 56, 32);
  EXPECT_THROW(DecodeYoloX(out, {128, 64}, 0.25f), Error);
}

TEST(PerClassNms, KeepsBestFirstAndCaps) {
  std::vector<Candidate> candidates = {{{0, 0, 10, 10}, 1, 0.5f, 0},
                                       {{1, 1, 10, 10}, 1, 0.7f, 1},  // overlap: keep 0.7
                                       {{50, 50, 10, 10}, 1, 0.6f, 2},
                                       {{0, 0, 10, 10}, 4, 0.9f, 3}};
  const auto kept = PerClassNms(candidates, 0.45f, 100);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0].anchor, 3);
  EXPECT_EQ(kept[1].anchor, 1);
  EXPECT_EQ(kept[2].anchor, 2);
  EXPECT_EQ(PerClassNms(candidates, 0.45f, 2).size(), 2u);
}

TEST(YoloV8InstanceMask, CoefficientsTimesPrototypesClippedToTheBox) {
  cv::Mat protos = Blob({1, 2, 4, 4}, 1.0f);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) At4(protos, 0, y, x) = x < 2 ? 5.0f : -5.0f;
  }
  const float coefficients[2] = {1.0f, -0.5f};  // logits 4.5 on the left half, -5.5 on the right
  const cv::Mat whole = YoloV8InstanceMask(protos, coefficients, {0, 0, 16, 16}, {16, 16}, 0.5f);
  ASSERT_EQ(whole.type(), CV_8U);
  EXPECT_EQ(whole.at<uchar>(8, 2), 255);
  EXPECT_EQ(whole.at<uchar>(8, 13), 0);
  EXPECT_NEAR(cv::countNonZero(whole), 16 * 8, 16);
  const cv::Mat clipped = YoloV8InstanceMask(protos, coefficients, {0, 0, 4, 16}, {16, 16}, 0.5f);
  EXPECT_EQ(clipped.at<uchar>(8, 2), 255);
  EXPECT_EQ(clipped.at<uchar>(8, 6), 0);
}

TEST(Letterbox, CentredAndTopLeftMapBack) {
  const Letterbox centred({640, 480}, {320, 256}, true);
  EXPECT_DOUBLE_EQ(centred.scale(), 0.5);
  EXPECT_EQ(centred.ContentRect(), cv::Rect(0, 8, 320, 240));
  const cv::Rect2f box = centred.ToOriginal({10, 18, 20, 20});
  EXPECT_FLOAT_EQ(box.x, 20);
  EXPECT_FLOAT_EQ(box.y, 20);
  EXPECT_FLOAT_EQ(box.width, 40);
  // Boxes reaching into the padding are clipped to the image.
  const cv::Rect2f clipped = centred.ToOriginal({-10, 0, 30, 30});
  EXPECT_FLOAT_EQ(clipped.x, 0);
  EXPECT_FLOAT_EQ(clipped.y, 0);
  EXPECT_FLOAT_EQ(clipped.height, 44);

  const Letterbox top_left({640, 480}, {320, 256}, false);
  EXPECT_EQ(top_left.ContentRect(), cv::Rect(0, 0, 320, 240));
  const cv::Mat padded = top_left.Apply(cv::Mat(480, 640, CV_8UC3, cv::Scalar(10, 20, 30)));
  EXPECT_EQ(padded.at<cv::Vec3b>(100, 100), cv::Vec3b(10, 20, 30));
  EXPECT_EQ(padded.at<cv::Vec3b>(250, 100), cv::Vec3b(114, 114, 114));
}

TEST(IoU, KnownOverlaps) {
  EXPECT_FLOAT_EQ(IoU({0, 0, 10, 10}, {0, 0, 10, 10}), 1.0f);
  EXPECT_FLOAT_EQ(IoU({0, 0, 10, 10}, {5, 0, 10, 10}), 50.0f / 150.0f);
  EXPECT_FLOAT_EQ(IoU({0, 0, 10, 10}, {20, 20, 5, 5}), 0.0f);
}

}  // namespace
}  // namespace noctua::dynamic
