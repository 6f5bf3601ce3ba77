#include "noctua/dynamic/decode.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "noctua/dynamic/detection.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

float Sigmoid(float x) { return 1.0f / (1.0f + std::exp(-x)); }

void CheckBlob(const cv::Mat& blob, int dims, const std::string& what) {
  if (blob.dims != dims || blob.type() != CV_32F || !blob.isContinuous() || blob.size[0] != 1) {
    throw Error(what + ": expected a continuous float tensor of " + std::to_string(dims) +
                " dimensions with batch 1");
  }
}

// Expected bin index under a softmax over `bins` values spaced `step` floats apart.
float DflDistance(const float* logits, int bins, size_t step) {
  float peak = logits[0];
  for (int b = 1; b < bins; ++b) peak = std::max(peak, logits[b * step]);
  float sum = 0.0f, weighted = 0.0f;
  for (int b = 0; b < bins; ++b) {
    const float e = std::exp(logits[b * step] - peak);
    sum += e;
    weighted += e * static_cast<float>(b);
  }
  return weighted / sum;
}

}  // namespace

float IoU(const cv::Rect2f& a, const cv::Rect2f& b) {
  const float inter = (a & b).area();
  const float uni = a.area() + b.area() - inter;
  return uni > 0.0f ? inter / uni : 0.0f;
}

std::vector<Candidate> DecodeYoloV8Head(const std::vector<YoloV8HeadLevel>& levels,
                                        float score_threshold) {
  std::vector<Candidate> out;
  // Comparing logits avoids a sigmoid per cell and class: sigmoid is monotonic.
  const float logit_threshold = std::log(score_threshold / std::max(1e-6f, 1.0f - score_threshold));
  int anchor_base = 0;
  for (const auto& level : levels) {
    CheckBlob(level.box_map, 4, "YOLOv8 box map");
    CheckBlob(level.class_map, 4, "YOLOv8 class map");
    const int h = level.class_map.size[2], w = level.class_map.size[3];
    const int classes = level.class_map.size[1];
    if (level.box_map.size[2] != h || level.box_map.size[3] != w ||
        level.box_map.size[1] % 4 != 0 || level.stride <= 0) {
      throw Error("YOLOv8 head: box and class maps of a stride disagree in size");
    }
    const int bins = level.box_map.size[1] / 4;
    const size_t plane = static_cast<size_t>(h) * w;
    const auto* cls = level.class_map.ptr<float>();
    const auto* box = level.box_map.ptr<float>();
    for (int gy = 0; gy < h; ++gy) {
      for (int gx = 0; gx < w; ++gx) {
        const size_t cell = static_cast<size_t>(gy) * w + gx;
        int best = 0;
        float best_logit = cls[cell];
        for (int c = 1; c < classes; ++c) {
          const float v = cls[c * plane + cell];
          if (v > best_logit) best_logit = v, best = c;
        }
        if (best_logit < logit_threshold) continue;
        float d[4];
        for (int side = 0; side < 4; ++side) {
          d[side] = DflDistance(box + static_cast<size_t>(side) * bins * plane + cell, bins, plane);
        }
        const float ax = gx + 0.5f, ay = gy + 0.5f, s = static_cast<float>(level.stride);
        const float x0 = (ax - d[0]) * s, y0 = (ay - d[1]) * s;
        const float x1 = (ax + d[2]) * s, y1 = (ay + d[3]) * s;
        out.push_back({cv::Rect2f(x0, y0, x1 - x0, y1 - y0), best, Sigmoid(best_logit),
                       anchor_base + static_cast<int>(cell)});
      }
    }
    anchor_base += static_cast<int>(plane);
  }
  return out;
}

std::vector<Candidate> DecodeYoloV8Stock(const cv::Mat& output, int num_classes,
                                         float score_threshold) {
  CheckBlob(output, 3, "YOLOv8 output");
  const int rows = output.size[1], n = output.size[2];
  if (rows < 4 + num_classes) {
    throw Error("YOLOv8 output has " + std::to_string(rows) + " rows, fewer than 4 + " +
                std::to_string(num_classes) + " classes");
  }
  const auto* data = output.ptr<float>();
  std::vector<Candidate> out;
  for (int i = 0; i < n; ++i) {
    int best = 0;
    float best_score = data[4 * static_cast<size_t>(n) + i];
    for (int c = 1; c < num_classes; ++c) {
      const float v = data[static_cast<size_t>(4 + c) * n + i];
      if (v > best_score) best_score = v, best = c;
    }
    if (best_score < score_threshold) continue;
    const float cx = data[i], cy = data[n + i];
    const float w = data[2 * static_cast<size_t>(n) + i], h = data[3 * static_cast<size_t>(n) + i];
    out.push_back({cv::Rect2f(cx - w / 2, cy - h / 2, w, h), best, best_score, i});
  }
  return out;
}

std::vector<Candidate> DecodeYoloX(const cv::Mat& output, cv::Size input_size,
                                   float score_threshold) {
  CheckBlob(output, 3, "YOLOX output");
  const int n = output.size[1], cols = output.size[2];
  const int classes = cols - 5;
  int expected = 0;
  for (int s : {8, 16, 32}) expected += (input_size.width / s) * (input_size.height / s);
  if (classes < 1 || n != expected) {
    throw Error("YOLOX output [1, " + std::to_string(n) + ", " + std::to_string(cols) +
                "] does not fit an input of " + std::to_string(input_size.width) + "x" +
                std::to_string(input_size.height) + " (expected " + std::to_string(expected) +
                " rows)");
  }
  const auto* data = output.ptr<float>();
  std::vector<Candidate> out;
  int row = 0;
  for (int s : {8, 16, 32}) {
    const int gw = input_size.width / s, gh = input_size.height / s;
    for (int gy = 0; gy < gh; ++gy) {
      for (int gx = 0; gx < gw; ++gx, ++row) {
        const float* r = data + static_cast<size_t>(row) * cols;
        if (r[4] < score_threshold) continue;  // score = objectness x class <= objectness
        int best = 0;
        for (int c = 1; c < classes; ++c) {
          if (r[5 + c] > r[5 + best]) best = c;
        }
        const float score = r[4] * r[5 + best];
        if (score < score_threshold) continue;
        const float cx = (r[0] + gx) * s, cy = (r[1] + gy) * s;
        const float w = std::exp(r[2]) * s, h = std::exp(r[3]) * s;
        out.push_back({cv::Rect2f(cx - w / 2, cy - h / 2, w, h), best, score, row});
      }
    }
  }
  return out;
}

std::vector<Candidate> PerClassNms(const std::vector<Candidate>& candidates, float iou_threshold,
                                   int max_count) {
  std::map<int, std::vector<int>> by_class;
  for (size_t i = 0; i < candidates.size(); ++i) {
    by_class[candidates[i].class_id].push_back(static_cast<int>(i));
  }
  std::vector<Candidate> kept;
  for (const auto& [class_id, members] : by_class) {
    std::vector<cv::Rect2d> boxes;
    std::vector<float> scores;
    for (int i : members) {
      boxes.emplace_back(candidates[i].box);
      scores.push_back(candidates[i].score);
    }
    std::vector<int> keep;
    cv::dnn::NMSBoxes(boxes, scores, 0.0f, iou_threshold, keep);
    for (int k : keep) kept.push_back(candidates[members[k]]);
  }
  std::stable_sort(kept.begin(), kept.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  if (static_cast<int>(kept.size()) > max_count) kept.resize(max_count);
  return kept;
}

cv::Mat YoloV8InstanceMask(const cv::Mat& prototypes, const float* coefficients,
                           const cv::Rect2f& box, cv::Size input_size, float threshold) {
  CheckBlob(prototypes, 4, "YOLOv8-seg prototypes");
  const int k = prototypes.size[1], h = prototypes.size[2], w = prototypes.size[3];
  const cv::Mat protos(k, h * w, CV_32F, const_cast<float*>(prototypes.ptr<float>()));
  const cv::Mat coeffs(1, k, CV_32F, const_cast<float*>(coefficients));
  const cv::Mat product = coeffs * protos;
  const cv::Mat logits = product.reshape(1, h);
  // Thresholding the logit at logit(threshold) equals thresholding the sigmoid.
  cv::Mat up;
  cv::resize(logits, up, input_size, 0, 0, cv::INTER_LINEAR);
  const double logit_threshold = std::log(threshold / (1.0 - threshold));
  cv::Mat mask = up > logit_threshold;
  const cv::Rect inside =
      cv::Rect(cvRound(box.x), cvRound(box.y), cvRound(box.width), cvRound(box.height)) &
      cv::Rect(cv::Point(), input_size);
  cv::Mat clipped = cv::Mat::zeros(input_size, CV_8U);
  if (!inside.empty()) mask(inside).copyTo(clipped(inside));
  return clipped;
}

}  // namespace noctua::dynamic
