#include "noctua/edges/edge_map.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

float Bilinear(const cv::Mat& image, float x, float y) {
  // Callers keep (x, y) inside the image; on its last row or column the far neighbour gets
  // weight 0 but is read from inside.
  const int x0 = std::min(static_cast<int>(std::floor(x)), image.cols - 2);
  const int y0 = std::min(static_cast<int>(std::floor(y)), image.rows - 2);
  const float fx = x - static_cast<float>(x0);
  const float fy = y - static_cast<float>(y0);
  const float* row0 = image.ptr<float>(y0);
  const float* row1 = image.ptr<float>(y0 + 1);
  return (1.0f - fy) * ((1.0f - fx) * row0[x0] + fx * row0[x0 + 1]) +
         fy * ((1.0f - fx) * row1[x0] + fx * row1[x0 + 1]);
}

// Offsets of the neighbour along the normal per whole degree, as Kovesi's nonmaxsup (his
// orientations are whole degrees): no trigonometry per pixel.
struct NormalOffsets {
  static constexpr int kBins = 180;
  float x[kBins];
  float y[kBins];
};

const NormalOffsets& Offsets() {
  static const NormalOffsets offsets = [] {
    NormalOffsets result{};
    for (int degree = 0; degree < NormalOffsets::kBins; ++degree) {
      const double angle = degree * std::numbers::pi / NormalOffsets::kBins;
      result.x[degree] = static_cast<float>(std::cos(angle));
      result.y[degree] = static_cast<float>(-std::sin(angle));  // y grows downwards
    }
    return result;
  }();
  return offsets;
}

// The unit normal at pixel (r, c), its orientation rounded to a whole degree.
cv::Point2f NormalAt(const cv::Mat& orientation, int r, int c) {
  const NormalOffsets& offsets = Offsets();
  const float to_bin = static_cast<float>(NormalOffsets::kBins / std::numbers::pi);
  const int bin =
      static_cast<int>(orientation.at<float>(r, c) * to_bin + 0.5f) % NormalOffsets::kBins;
  return {offsets.x[bin], offsets.y[bin]};
}

// Whether interior pixel (r, c) is a maximum along its normal: strictly above the neighbour ahead,
// at least the one behind (so a symmetric two-pixel ridge keeps one pixel).
bool IsNormalMaximum(const cv::Mat& strength, const cv::Mat& orientation, int r, int c) {
  const float value = strength.at<float>(r, c);
  const cv::Point2f normal = NormalAt(orientation, r, c);
  const float x = static_cast<float>(c);
  const float y = static_cast<float>(r);
  if (!(value > Bilinear(strength, x + normal.x, y + normal.y))) return false;
  return value >= Bilinear(strength, x - normal.x, y - normal.y);
}

// Marks the 8-connected line between two placed edge pixels. The pixels of cv::line (whose
// iterator this is) without its per-call overhead, which is most of its cost for lines this short.
void JoinWithLine(cv::Mat& map, const cv::Vec2i& from, const cv::Vec2i& to) {
  cv::LineIterator line(map, cv::Point(from[0], from[1]), cv::Point(to[0], to[1]), 8, true);
  for (int i = 0; i < line.count; ++i, ++line) **line = 255;
}

}  // namespace

void EdgeMapOptions::Check() const {
  CheckOption(low_threshold >= 0.0 && low_threshold <= 1.0, "low_threshold must be in [0, 1]");
  CheckOption(high_threshold >= low_threshold && high_threshold <= 1.0,
              "high_threshold must be in [low_threshold, 1]");
}

cv::Mat NonMaximumSuppression(const cv::Mat& strength, const cv::Mat& orientation,
                              double min_strength) {
  if (strength.type() != CV_32F || orientation.type() != CV_32F ||
      strength.size() != orientation.size()) {
    throw Error("non-maximum suppression: strength and orientation must be CV_32F of one size");
  }
  const float floor_value = std::max(static_cast<float>(min_strength), 1e-7f);
  cv::Mat thinned = cv::Mat::zeros(strength.size(), CV_32F);
  // Neighbours lie within one pixel, so the loop stays one pixel inside the image and the
  // bilinear reads stay inside it.
  for (int r = 1; r + 1 < strength.rows; ++r) {
    const float* s = strength.ptr<float>(r);
    float* out = thinned.ptr<float>(r);
    for (int c = 1; c + 1 < strength.cols; ++c) {
      if (s[c] >= floor_value && IsNormalMaximum(strength, orientation, r, c)) {
        out[c] = s[c];
      }
    }
  }
  return thinned;
}

cv::Mat HysteresisThreshold(const cv::Mat& strength, double low, double high) {
  if (strength.type() != CV_32F) throw Error("hysteresis: strength must be CV_32F");
  if (low > high) throw Error("hysteresis: low threshold above high threshold");
  // Zero never belongs to an edge, even with a zero low threshold.
  const float weak = std::max(static_cast<float>(low), 1e-7f);
  const float strong = std::max(static_cast<float>(high), weak);
  const int rows = strength.rows;
  const int cols = strength.cols;
  cv::Mat edges = cv::Mat::zeros(strength.size(), CV_8U);
  // Grows each edge from its strong pixels over 8-connected weak ones; the edge pixels are a
  // few percent of the image, so a stack beats labelling every component.
  std::vector<cv::Point> stack;
  for (int r = 0; r < rows; ++r) {
    const float* s = strength.ptr<float>(r);
    for (int c = 0; c < cols; ++c) {
      if (s[c] < strong || edges.at<unsigned char>(r, c) != 0) continue;
      edges.at<unsigned char>(r, c) = 255;
      stack.emplace_back(c, r);
      while (!stack.empty()) {
        const cv::Point p = stack.back();
        stack.pop_back();
        for (int y = std::max(p.y - 1, 0); y <= std::min(p.y + 1, rows - 1); ++y) {
          const float* sy = strength.ptr<float>(y);
          unsigned char* ey = edges.ptr<unsigned char>(y);
          for (int x = std::max(p.x - 1, 0); x <= std::min(p.x + 1, cols - 1); ++x) {
            if (ey[x] == 0 && sy[x] >= weak) {
              ey[x] = 255;
              stack.emplace_back(x, y);
            }
          }
        }
      }
    }
  }
  return edges;
}

cv::Mat EdgeMapFromPhaseCongruency(const PhaseCongruency& pc, const EdgeMapOptions& options) {
  options.Check();
  const cv::Mat& strength = pc.max_moment;
  const cv::Mat& orientation = pc.orientation;
  if (strength.type() != CV_32F || orientation.type() != CV_32F ||
      strength.size() != orientation.size()) {
    throw Error("edge map: PC and orientation must be CV_32F of one size");
  }
  // HysteresisThreshold(NonMaximumSuppression(M, orientation, low), low, high) in one pass:
  // NMS is evaluated only on the pixels hysteresis reaches (those >= low next to an edge), not
  // on the whole frame. state: 0 unvisited, 1 not an edge, 255 edge.
  const float weak = std::max(static_cast<float>(options.low_threshold), 1e-7f);
  const float strong = std::max(static_cast<float>(options.high_threshold), weak);
  const int rows = strength.rows;
  const int cols = strength.cols;
  cv::Mat state = cv::Mat::zeros(strength.size(), CV_8U);
  std::vector<cv::Point> stack;
  auto visit = [&](int r, int c) {
    unsigned char& s = state.at<unsigned char>(r, c);
    if (s != 0) return;
    const bool edge =
        strength.at<float>(r, c) >= weak && IsNormalMaximum(strength, orientation, r, c);
    s = edge ? 255 : 1;
    if (edge) stack.emplace_back(c, r);
  };
  for (int r = 1; r + 1 < rows; ++r) {
    const float* s = strength.ptr<float>(r);
    for (int c = 1; c + 1 < cols; ++c) {
      if (s[c] < strong) continue;
      visit(r, c);
      while (!stack.empty()) {
        const cv::Point p = stack.back();
        stack.pop_back();
        for (int y = std::max(p.y - 1, 1); y <= std::min(p.y + 1, rows - 2); ++y) {
          for (int x = std::max(p.x - 1, 1); x <= std::min(p.x + 1, cols - 2); ++x) visit(y, x);
        }
      }
    }
  }
  cv::threshold(state, state, 254, 255, cv::THRESH_BINARY);
  return state;
}

cv::Mat EnlargeEdgeMap(const cv::Mat& edges, const PhaseCongruency& pc, cv::Size full_size,
                       int factor) {
  const cv::Mat& strength = pc.max_moment;
  const cv::Mat& orientation = pc.orientation;
  if (edges.type() != CV_8U || strength.type() != CV_32F || orientation.type() != CV_32F ||
      edges.size() != strength.size() || edges.size() != orientation.size()) {
    throw Error("edge map enlargement: edges (CV_8U) and PC (CV_32F) must be of one size");
  }
  if (factor < 1 || full_size.width / factor != edges.cols ||
      full_size.height / factor != edges.rows) {
    throw Error("edge map enlargement: the reduced map is not the full size divided by " +
                std::to_string(factor));
  }
  const auto scale = static_cast<float>(factor);
  const int rows = edges.rows;
  const int cols = edges.cols;
  // Where each edge pixel lands in the full map, written (and read) at edge pixels only, so it
  // is never cleared. (Not kept per thread: the extractor makes each edge map on a new thread.)
  cv::Mat placed(edges.size(), CV_32SC2);
  std::vector<cv::Point> edge_pixels;
  cv::findNonZero(edges, edge_pixels);
  cv::Mat full = cv::Mat::zeros(full_size, CV_8U);
  for (const cv::Point& pixel : edge_pixels) {
    const int r = pixel.y;
    const int c = pixel.x;
    const auto x = static_cast<float>(c);
    const auto y = static_cast<float>(r);
    cv::Point2f shift(0.0f, 0.0f);  // towards the peak along the normal
    // Border pixels lack a neighbour on one side and stay at their centre.
    if (r > 0 && c > 0 && r + 1 < rows && c + 1 < cols) {
      const cv::Point2f normal = NormalAt(orientation, r, c);
      const float ahead = Bilinear(strength, x + normal.x, y + normal.y);
      const float behind = Bilinear(strength, x - normal.x, y - normal.y);
      const float curvature = behind - 2.0f * strength.at<float>(r, c) + ahead;
      if (curvature < 0.0f) {
        shift = normal * std::clamp(0.5f * (behind - ahead) / curvature, -0.5f, 0.5f);
      }
    }
    const float full_x = (x + shift.x + 0.5f) * scale - 0.5f;
    const float full_y = (y + shift.y + 0.5f) * scale - 0.5f;
    placed.at<cv::Vec2i>(pixel) =
        cv::Vec2i(std::clamp(static_cast<int>(std::lround(full_x)), 0, full_size.width - 1),
                  std::clamp(static_cast<int>(std::lround(full_y)), 0, full_size.height - 1));
  }
  for (const cv::Point& pixel : edge_pixels) {
    const cv::Vec2i from = placed.at<cv::Vec2i>(pixel);
    full.at<unsigned char>(from[1], from[0]) = 255;
    // Each pair of 8-neighbours once: right, and the three below.
    constexpr int kForward[4][2] = {{0, 1}, {1, -1}, {1, 0}, {1, 1}};
    for (const auto& [dr, dc] : kForward) {
      const int rr = pixel.y + dr;
      const int cc = pixel.x + dc;
      if (rr >= rows || cc < 0 || cc >= cols || edges.at<unsigned char>(rr, cc) == 0) continue;
      JoinWithLine(full, from, placed.at<cv::Vec2i>(rr, cc));
    }
  }
  return full;
}

}  // namespace noctua::edges

namespace noctua::edges {

EdgeAgreement CompareEdgeMaps(const cv::Mat& test, const cv::Mat& reference, int tolerance_px) {
  if (test.type() != CV_8U || reference.type() != CV_8U || test.size() != reference.size()) {
    throw Error("edge comparison: both maps must be CV_8U of one size");
  }
  if (tolerance_px < 0) throw Error("edge comparison: tolerance must be >= 0");
  const cv::Mat kernel = cv::getStructuringElement(
      cv::MORPH_RECT, cv::Size(2 * tolerance_px + 1, 2 * tolerance_px + 1));
  const cv::Mat test_on = test != 0;
  const cv::Mat reference_on = reference != 0;
  cv::Mat test_near;
  cv::Mat reference_near;
  cv::dilate(test_on, test_near, kernel);
  cv::dilate(reference_on, reference_near, kernel);
  EdgeAgreement result;
  result.test_pixels = cv::countNonZero(test_on);
  result.reference_pixels = cv::countNonZero(reference_on);
  if (result.test_pixels == 0 && result.reference_pixels == 0) {
    result.precision = result.recall = result.f_measure = 1.0;
    return result;
  }
  if (result.test_pixels > 0) {
    result.precision =
        static_cast<double>(cv::countNonZero(test_on & reference_near)) / result.test_pixels;
  }
  if (result.reference_pixels > 0) {
    result.recall =
        static_cast<double>(cv::countNonZero(reference_on & test_near)) / result.reference_pixels;
  }
  const double sum = result.precision + result.recall;
  result.f_measure = sum > 0.0 ? 2.0 * result.precision * result.recall / sum : 0.0;
  return result;
}

}  // namespace noctua::edges
