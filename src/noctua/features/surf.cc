#include "noctua/features/surf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "noctua/image/enhancement.h"
#include "noctua/util/error.h"

namespace noctua::features {

void SurfOptions::Check() const {
  CheckOption(hessian_threshold >= 0.0, "surf hessian_threshold must be non-negative");
  CheckOption(num_octaves >= 1 && num_octaves <= 8, "surf num_octaves must be in [1, 8]");
  CheckOption(num_octave_layers >= 1 && num_octave_layers <= 8,
              "surf num_octave_layers must be in [1, 8]");
  CheckOption(max_features >= 0, "surf max_features must be 0 (all) or positive");
}

namespace {

// Integral image with a zero first row and column: the sum over [x0, x1) x [y0, y1).
class Integral {
 public:
  explicit Integral(const cv::Mat& gray) { cv::integral(gray, sum_, CV_64F); }
  int cols() const { return sum_.cols - 1; }
  int rows() const { return sum_.rows - 1; }
  double Box(int x0, int y0, int x1, int y1) const {
    return sum_.at<double>(y1, x1) - sum_.at<double>(y0, x1) - sum_.at<double>(y1, x0) +
           sum_.at<double>(y0, x0);
  }
  // Box clipped to the image (an empty box sums to 0).
  double ClippedBox(int x0, int y0, int x1, int y1) const {
    x0 = std::clamp(x0, 0, cols());
    x1 = std::clamp(x1, 0, cols());
    y0 = std::clamp(y0, 0, rows());
    y1 = std::clamp(y1, 0, rows());
    return x1 > x0 && y1 > y0 ? Box(x0, y0, x1, y1) : 0.0;
  }
  // Box of size w x h whose top-left corner is at the real-valued (x, y): bilinear blend of the
  // four integer-aligned boxes around it, so that sampling does not jump by whole pixels.
  double SubpixelBox(double x, double y, int w, int h) const {
    const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
    const double fx = x - xi, fy = y - yi;
    return (1 - fx) * (1 - fy) * ClippedBox(xi, yi, xi + w, yi + h) +
           fx * (1 - fy) * ClippedBox(xi + 1, yi, xi + 1 + w, yi + h) +
           (1 - fx) * fy * ClippedBox(xi, yi + 1, xi + w, yi + 1 + h) +
           fx * fy * ClippedBox(xi + 1, yi + 1, xi + 1 + w, yi + 1 + h);
  }

 private:
  cv::Mat sum_;
};

// A box of the 9x9 second-derivative filters: [x0, x1) x [y0, y1) with a weight.
struct HaarBox {
  int x0, y0, x1, y1;
  double weight;
};

// Bay et al.'s 9x9 approximations of the Gaussian second derivatives (sigma 1.2), in OpenCV's
// layout, scaled to `size` with each box's weight divided by its area.
std::vector<HaarBox> ScaledPattern(const std::vector<std::array<int, 5>>& pattern, int size) {
  const double ratio = size / 9.0;
  std::vector<HaarBox> boxes;
  for (const auto& p : pattern) {
    HaarBox box{static_cast<int>(std::lround(ratio * p[0])),
                static_cast<int>(std::lround(ratio * p[1])),
                static_cast<int>(std::lround(ratio * p[2])),
                static_cast<int>(std::lround(ratio * p[3])), 0.0};
    box.weight = p[4] / static_cast<double>((box.x1 - box.x0) * (box.y1 - box.y0));
    boxes.push_back(box);
  }
  return boxes;
}

double Response(const Integral& integral, const std::vector<HaarBox>& boxes, int left, int top) {
  double value = 0.0;
  for (const auto& b : boxes) {
    value += b.weight * integral.Box(left + b.x0, top + b.y0, left + b.x1, top + b.y1);
  }
  return value;
}

// Determinant of the Hessian (and the Laplacian's sign) on one scale layer, sampled every `step`
// pixels: grid point (i, j) is the filter centred on pixel (j * step, i * step).
struct Layer {
  int size = 0;
  cv::Mat det;    // CV_64F, 0 where the filter does not fit
  cv::Mat trace;  // CV_64F
};

Layer ComputeLayer(const Integral& integral, int size, int step) {
  static const std::vector<std::array<int, 5>> kDxx = {
      {0, 2, 3, 7, 1}, {3, 2, 6, 7, -2}, {6, 2, 9, 7, 1}};
  static const std::vector<std::array<int, 5>> kDyy = {
      {2, 0, 7, 3, 1}, {2, 3, 7, 6, -2}, {2, 6, 7, 9, 1}};
  static const std::vector<std::array<int, 5>> kDxy = {
      {1, 1, 4, 4, 1}, {5, 1, 8, 4, -1}, {1, 5, 4, 8, -1}, {5, 5, 8, 8, 1}};
  const auto dxx = ScaledPattern(kDxx, size);
  const auto dyy = ScaledPattern(kDyy, size);
  const auto dxy = ScaledPattern(kDxy, size);
  const int grid_rows = (integral.rows() + step - 1) / step;
  const int grid_cols = (integral.cols() + step - 1) / step;
  Layer layer;
  layer.size = size;
  layer.det = cv::Mat(grid_rows, grid_cols, CV_64F, cv::Scalar(0));
  layer.trace = cv::Mat(grid_rows, grid_cols, CV_64F, cv::Scalar(0));
  const int half = size / 2;
  for (int i = 0; i < grid_rows; ++i) {
    const int top = i * step - half;
    if (top < 0 || top + size > integral.rows()) continue;
    for (int j = 0; j < grid_cols; ++j) {
      const int left = j * step - half;
      if (left < 0 || left + size > integral.cols()) continue;
      const double xx = Response(integral, dxx, left, top);
      const double yy = Response(integral, dyy, left, top);
      const double xy = Response(integral, dxy, left, top);
      // 0.9 balances the box approximation's relative weights (Bay et al., eq. 4): 0.81 = 0.9^2.
      layer.det.at<double>(i, j) = xx * yy - 0.81 * xy * xy;
      layer.trace.at<double>(i, j) = xx + yy;
    }
  }
  return layer;
}

bool IsLocalMaximum(const std::array<const Layer*, 3>& layers, int i, int j, double value) {
  for (const Layer* layer : layers) {
    for (int di = -1; di <= 1; ++di) {
      const double* row = layer->det.ptr<double>(i + di);
      for (int dj = -1; dj <= 1; ++dj) {
        if (layer == layers[1] && di == 0 && dj == 0) continue;
        if (row[j + dj] >= value) return false;
      }
    }
  }
  return true;
}

// Fits a 3D quadratic to the determinant around (layer, i, j); false when the offset leaves the
// sample cell (the maximum is not well localised there).
bool Interpolate(const std::array<const Layer*, 3>& l, int i, int j, cv::Vec3d& offset) {
  auto d = [&](int layer, int di, int dj) { return l[layer]->det.at<double>(i + di, j + dj); };
  const cv::Vec3d gradient((d(1, 0, 1) - d(1, 0, -1)) / 2.0, (d(1, 1, 0) - d(1, -1, 0)) / 2.0,
                           (d(2, 0, 0) - d(0, 0, 0)) / 2.0);
  const double centre = d(1, 0, 0);
  const double dxx = d(1, 0, 1) + d(1, 0, -1) - 2.0 * centre;
  const double dyy = d(1, 1, 0) + d(1, -1, 0) - 2.0 * centre;
  const double dss = d(2, 0, 0) + d(0, 0, 0) - 2.0 * centre;
  const double dxy = (d(1, 1, 1) - d(1, 1, -1) - d(1, -1, 1) + d(1, -1, -1)) / 4.0;
  const double dxs = (d(2, 0, 1) - d(2, 0, -1) - d(0, 0, 1) + d(0, 0, -1)) / 4.0;
  const double dys = (d(2, 1, 0) - d(2, -1, 0) - d(0, 1, 0) + d(0, -1, 0)) / 4.0;
  const cv::Matx33d hessian(dxx, dxy, dxs, dxy, dyy, dys, dxs, dys, dss);
  cv::Vec3d solution;
  if (!cv::solve(hessian, -gradient, solution, cv::DECOMP_LU)) return false;
  offset = solution;
  return std::abs(offset[0]) <= 1.0 && std::abs(offset[1]) <= 1.0 && std::abs(offset[2]) <= 1.0;
}

std::vector<cv::KeyPoint> Detect(const Integral& integral, const SurfOptions& options) {
  std::vector<cv::KeyPoint> keypoints;
  const int layers_per_octave = options.num_octave_layers + 2;
  for (int octave = 0; octave < options.num_octaves; ++octave) {
    const int step = 1 << octave;
    std::vector<Layer> layers;
    for (int l = 0; l < layers_per_octave; ++l) {
      const int size = (9 + 6 * l) << octave;
      if (size >= std::min(integral.rows(), integral.cols())) break;
      layers.push_back(ComputeLayer(integral, size, step));
    }
    for (std::size_t l = 1; l + 1 < layers.size(); ++l) {
      const std::array<const Layer*, 3> around = {&layers[l - 1], &layers[l], &layers[l + 1]};
      // The largest filter of the three must fit around the point and its neighbours.
      const int margin = (layers[l + 1].size / 2) / step + 1;
      const cv::Mat& det = layers[l].det;
      for (int i = margin; i < det.rows - margin; ++i) {
        for (int j = margin; j < det.cols - margin; ++j) {
          const double value = det.at<double>(i, j);
          if (value <= options.hessian_threshold || !IsLocalMaximum(around, i, j, value)) continue;
          cv::Vec3d offset;
          if (!Interpolate(around, i, j, offset)) continue;
          const double size_step = layers[l].size - layers[l - 1].size;
          cv::KeyPoint keypoint(static_cast<float>((j + offset[0]) * step),
                                static_cast<float>((i + offset[1]) * step),
                                static_cast<float>(layers[l].size + offset[2] * size_step), -1.0f,
                                static_cast<float>(value), octave);
          const double trace = layers[l].trace.at<double>(i, j);
          keypoint.class_id = trace > 0 ? 1 : (trace < 0 ? -1 : 0);
          keypoints.push_back(keypoint);
        }
      }
    }
  }
  return keypoints;
}

// Haar wavelet responses of side `side` centred on (x, y): right minus left, bottom minus top.
void Haar(const Integral& integral, double x, double y, int side, double& hx, double& hy) {
  const double x0 = x - side / 2.0, y0 = y - side / 2.0;
  const int half = side / 2;
  hx = integral.SubpixelBox(x0 + half, y0, side - half, side) -
       integral.SubpixelBox(x0, y0, half, side);
  hy = integral.SubpixelBox(x0, y0 + half, side, side - half) -
       integral.SubpixelBox(x0, y0, side, half);
}

float Orientation(const Integral& integral, const cv::KeyPoint& keypoint) {
  const double s = keypoint.size * 1.2 / 9.0;
  const int side = std::max(2, 2 * static_cast<int>(std::lround(2.0 * s)));  // 4s, even
  std::vector<double> angles, xs, ys;
  for (int i = -6; i <= 6; ++i) {
    for (int j = -6; j <= 6; ++j) {
      if (i * i + j * j > 36) continue;
      double hx, hy;
      Haar(integral, keypoint.pt.x + j * s, keypoint.pt.y + i * s, side, hx, hy);
      const double weight = std::exp(-(i * i + j * j) / (2.0 * 2.0 * 2.0));  // sigma = 2s
      xs.push_back(weight * hx);
      ys.push_back(weight * hy);
      angles.push_back(std::atan2(ys.back(), xs.back()));
    }
  }
  // The direction of the largest summed response in a window of pi/3 sliding in 5 degree steps.
  double best = -1.0, best_x = 1.0, best_y = 0.0;
  for (int step = 0; step < 72; ++step) {
    const double centre = step * 5.0 * std::numbers::pi / 180.0;
    double sx = 0.0, sy = 0.0;
    for (std::size_t k = 0; k < angles.size(); ++k) {
      double diff = std::abs(angles[k] - centre);
      if (diff > std::numbers::pi) diff = 2.0 * std::numbers::pi - diff;
      if (diff < std::numbers::pi / 6.0) {
        sx += xs[k];
        sy += ys[k];
      }
    }
    if (sx * sx + sy * sy > best) {
      best = sx * sx + sy * sy;
      best_x = sx;
      best_y = sy;
    }
  }
  double degrees = std::atan2(best_y, best_x) * 180.0 / std::numbers::pi;
  if (degrees < 0.0) degrees += 360.0;
  return static_cast<float>(degrees);
}

void Describe(const Integral& integral, const cv::KeyPoint& keypoint, float* out) {
  const double s = keypoint.size * 1.2 / 9.0;
  const double theta = keypoint.angle * std::numbers::pi / 180.0;
  const double c = std::cos(theta), sn = std::sin(theta);
  const int box = std::max(1, static_cast<int>(std::lround(s)));
  // 21 x 21 samples, s apart, on the grid turned to the keypoint's orientation; each the mean of
  // an s x s box (the integral image makes that one lookup, and it avoids aliasing at coarse
  // scales).
  constexpr int kSamples = 21;
  double patch[kSamples][kSamples];
  for (int v = 0; v < kSamples; ++v) {
    for (int u = 0; u < kSamples; ++u) {
      const double ox = (u - 10) * s, oy = (v - 10) * s;
      const double x = keypoint.pt.x + c * ox - sn * oy;
      const double y = keypoint.pt.y + sn * ox + c * oy;
      patch[v][u] = integral.SubpixelBox(x - box / 2.0, y - box / 2.0, box, box) / (box * box);
    }
  }
  std::fill(out, out + 64, 0.0f);
  for (int v = 0; v < 20; ++v) {
    for (int u = 0; u < 20; ++u) {
      const double dx = (patch[v][u + 1] - patch[v][u] + patch[v + 1][u + 1] - patch[v + 1][u]) / 2;
      const double dy = (patch[v + 1][u] - patch[v][u] + patch[v + 1][u + 1] - patch[v][u + 1]) / 2;
      const double r2 = (u - 9.5) * (u - 9.5) + (v - 9.5) * (v - 9.5);
      const double weight = std::exp(-r2 / (2.0 * 3.3 * 3.3));
      float* cell = out + 4 * ((v / 5) * 4 + (u / 5));
      cell[0] += static_cast<float>(weight * dx);
      cell[1] += static_cast<float>(weight * std::abs(dx));
      cell[2] += static_cast<float>(weight * dy);
      cell[3] += static_cast<float>(weight * std::abs(dy));
    }
  }
  double norm = 0.0;
  for (int k = 0; k < 64; ++k) norm += out[k] * out[k];
  norm = std::sqrt(norm);
  if (norm > 0.0) {
    for (int k = 0; k < 64; ++k) out[k] = static_cast<float>(out[k] / norm);
  }
}

}  // namespace

cv::Ptr<Surf> Surf::Create(const SurfOptions& options) { return cv::makePtr<Surf>(options); }

Surf::Surf(const SurfOptions& options) : options_(options) { options_.Check(); }

void Surf::detectAndCompute(cv::InputArray image, cv::InputArray mask,
                            std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                            bool useProvidedKeypoints) {
  const cv::Mat gray = image::ToGray8U(image.getMat());
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != gray.size())) {
    throw Error("surf: the mask must be CV_8U of the image's size");
  }
  const Integral integral(gray);
  if (!useProvidedKeypoints) {
    keypoints = Detect(integral, options_);
    if (!mask.empty()) cv::KeyPointsFilter::runByPixelsMask(keypoints, mask.getMat());
    if (options_.max_features > 0)
      cv::KeyPointsFilter::retainBest(keypoints, options_.max_features);
    if (options_.max_features > 0 && static_cast<int>(keypoints.size()) > options_.max_features) {
      keypoints.resize(static_cast<std::size_t>(options_.max_features));
    }
    for (auto& keypoint : keypoints) keypoint.angle = Orientation(integral, keypoint);
  } else {
    for (auto& keypoint : keypoints) {
      if (keypoint.angle < 0.0f) keypoint.angle = Orientation(integral, keypoint);
    }
  }
  if (!descriptors.needed()) return;
  descriptors.create(static_cast<int>(keypoints.size()), 64, CV_32F);
  cv::Mat out = descriptors.getMat();
  cv::parallel_for_(cv::Range(0, static_cast<int>(keypoints.size())), [&](const cv::Range& r) {
    for (int k = r.start; k < r.end; ++k) {
      Describe(integral, keypoints[static_cast<std::size_t>(k)], out.ptr<float>(k));
    }
  });
}

}  // namespace noctua::features
