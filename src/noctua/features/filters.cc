#include "noctua/features/filters.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

namespace noctua::features {

cv::Point ToLevelZeroPixel(const cv::KeyPoint& point, double scale, const cv::Size& size) {
  const int x = cvRound(point.pt.x * scale);
  const int y = cvRound(point.pt.y * scale);
  return {std::clamp(x, 0, size.width - 1), std::clamp(y, 0, size.height - 1)};
}

void FilterByMask(std::vector<cv::KeyPoint>& points, double scale, const cv::Mat& mask,
                  bool drop_where_set) {
  CV_Assert(mask.type() == CV_8UC1);
  std::erase_if(points, [&](const cv::KeyPoint& point) {
    const bool set = mask.at<uchar>(ToLevelZeroPixel(point, scale, mask.size())) != 0;
    return set == drop_where_set;
  });
}

void FilterByEdgeDistance(std::vector<cv::KeyPoint>& points, double scale, const cv::Mat& edge_map,
                          double radius_px, std::vector<cv::KeyPoint>* dropped) {
  CV_Assert(edge_map.type() == CV_8UC1);
  const double limit = radius_px * scale;
  const double limit_squared = limit * limit;
  const int reach = static_cast<int>(std::floor(limit));
  // half_width[|dy|]: the largest dx with dx^2 + dy^2 <= limit^2, so that the pixels looked at are
  // exactly the disc of radius `limit` around the point.
  std::vector<int> half_width(static_cast<std::size_t>(reach) + 1);
  for (int dy = 0; dy <= reach; ++dy) {
    int w = static_cast<int>(std::floor(std::sqrt(std::max(limit_squared - dy * dy, 0.0))));
    while (w > 0 && static_cast<double>(w * w + dy * dy) > limit_squared) --w;
    while (static_cast<double>((w + 1) * (w + 1) + dy * dy) <= limit_squared) ++w;
    half_width[static_cast<std::size_t>(dy)] = w;
  }
  const int rows = edge_map.rows;
  const int cols = edge_map.cols;
  auto edge_in_row = [&](int y, int x, int dy) {
    if (y < 0 || y >= rows) return false;
    const int w = half_width[static_cast<std::size_t>(std::abs(dy))];
    const uchar* row = edge_map.ptr<uchar>(y);
    const int end = std::min(x + w, cols - 1);
    for (int c = std::max(x - w, 0); c <= end; ++c) {
      if (row[c] != 0) return true;
    }
    return false;
  };
  std::erase_if(points, [&](const cv::KeyPoint& point) {
    const cv::Point p = ToLevelZeroPixel(point, scale, edge_map.size());
    // Nearest rows first: most kept points have an edge pixel within a row or two.
    if (edge_in_row(p.y, p.x, 0)) return false;
    for (int dy = 1; dy <= reach; ++dy) {
      if (edge_in_row(p.y - dy, p.x, dy) || edge_in_row(p.y + dy, p.x, dy)) return false;
    }
    if (dropped) dropped->push_back(point);
    return true;
  });
}

namespace {

cv::Point ClampedPixel(const cv::KeyPoint& point, const cv::Size& size) {
  return {std::clamp(cvRound(point.pt.x), 0, size.width - 1),
          std::clamp(cvRound(point.pt.y), 0, size.height - 1)};
}

// Greedy suppression, strongest first: a point survives only if no stronger survivor and no
// `claimed` point lies inside its window.
void SuppressAgainst(std::vector<cv::KeyPoint>& points, const std::vector<cv::KeyPoint>& claimed,
                     const cv::Size& level_size, int window) {
  if (points.empty() || (claimed.empty() && points.size() < 2)) return;
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return points[a].response > points[b].response;
  });
  const int radius = window / 2;
  cv::Mat taken(level_size, CV_8UC1, cv::Scalar(0));
  for (const cv::KeyPoint& point : claimed) taken.at<uchar>(ClampedPixel(point, level_size)) = 1;
  std::vector<cv::KeyPoint> kept;
  kept.reserve(points.size());
  for (const std::size_t index : order) {
    const cv::KeyPoint& point = points[index];
    const cv::Point p = ClampedPixel(point, level_size);
    bool suppressed = false;
    for (int dy = -radius; dy <= radius && !suppressed; ++dy) {
      const int yy = p.y + dy;
      if (yy < 0 || yy >= level_size.height) continue;
      const uchar* row = taken.ptr<uchar>(yy);
      for (int dx = -radius; dx <= radius; ++dx) {
        const int xx = p.x + dx;
        if (xx >= 0 && xx < level_size.width && row[xx]) {
          suppressed = true;
          break;
        }
      }
    }
    if (suppressed) continue;
    taken.at<uchar>(p) = 1;
    kept.push_back(point);
  }
  points = std::move(kept);
}

}  // namespace

std::vector<cv::KeyPoint> FillCandidates(std::vector<cv::KeyPoint> dropped,
                                         const std::vector<cv::KeyPoint>& kept,
                                         const cv::Size& level_size, int window) {
  // One suppression in which the kept points have already claimed their windows: a dropped
  // point next to a kept one never survives, so it suppresses no other.
  SuppressAgainst(dropped, kept, level_size, window);
  return dropped;
}

void SuppressNonMaxima(std::vector<cv::KeyPoint>& points, const cv::Size& level_size, int window) {
  SuppressAgainst(points, {}, level_size, window);
}

}  // namespace noctua::features
