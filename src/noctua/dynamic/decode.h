#pragma once

#include <opencv2/core.hpp>
#include <vector>

// Decoders of the raw network outputs, separate from the networks so that each is tested on
// tensors built by hand with known boxes. All boxes are in letterboxed input pixels.
namespace noctua::dynamic {

struct Candidate {
  cv::Rect2f box;  // input pixels
  int class_id = 0;
  float score = 0.0f;
  int anchor = 0;  // index of the anchor (grid cell over all strides): finds its mask coefficients
};

// One stride of a YOLOv8 head export: box-side distributions [1, 4*bins, h, w] (left, top, right,
// bottom; `bins` = 16 for the stock weights) and class logits [1, C, h, w].
struct YoloV8HeadLevel {
  cv::Mat box_map;
  cv::Mat class_map;
  int stride = 0;
};

// YOLOv8 head decoding: class score = sigmoid(logit); each side's distance is the expected bin
// under a softmax over its bins (DFL); anchor = cell centre; box = anchor -/+ distances, times the
// stride. Anchors are numbered level by level, row-major, in the order given.
std::vector<Candidate> DecodeYoloV8Head(const std::vector<YoloV8HeadLevel>& levels,
                                        float score_threshold);

// Stock Ultralytics single output [1, 4 + C (+ extra), N]: rows cx, cy, w, h, then C class
// scores (already sigmoid), then `extra` rows (32 mask coefficients for -seg) that are ignored.
std::vector<Candidate> DecodeYoloV8Stock(const cv::Mat& output, int num_classes,
                                         float score_threshold);

// YOLOX output [1, N, 5 + C], rows in stride order (8, 16, 32), row-major per grid of the input
// size: (x, y, log w, log h, objectness, C class scores), probabilities already sigmoid.
std::vector<Candidate> DecodeYoloX(const cv::Mat& output, cv::Size input_size,
                                   float score_threshold);

// Per-class non-maximum suppression: keeps, best first, at most `max_count` candidates that
// overlap no better-scored candidate of the same class by more than `iou_threshold`.
std::vector<Candidate> PerClassNms(const std::vector<Candidate>& candidates, float iou_threshold,
                                   int max_count);

// Instance mask of one YOLOv8-seg candidate in input pixels: sigmoid(coefficients . prototypes)
// upsampled from the prototype grid [1, K, h, w] to `input_size`, > `threshold`, clipped to the
// box. `coefficients` holds K floats. Returns CV_8U 0/255 of `input_size`.
cv::Mat YoloV8InstanceMask(const cv::Mat& prototypes, const float* coefficients,
                           const cv::Rect2f& box, cv::Size input_size, float threshold);

}  // namespace noctua::dynamic
