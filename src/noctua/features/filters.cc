#include "noctua/features/filters.h"

#include <algorithm>
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

cv::Mat DistanceToEdges(const cv::Mat& edge_map) {
  CV_Assert(edge_map.type() == CV_8UC1);
  cv::Mat non_edge = edge_map == 0;
  cv::Mat distance;
  cv::distanceTransform(non_edge, distance, cv::DIST_L2, cv::DIST_MASK_5);
  return distance;
}

void FilterByEdgeDistance(std::vector<cv::KeyPoint>& points, double scale,
                          const cv::Mat& distance_to_edges, double radius_px) {
  CV_Assert(distance_to_edges.type() == CV_32FC1);
  const float limit = static_cast<float>(radius_px * scale);
  std::erase_if(points, [&](const cv::KeyPoint& point) {
    return distance_to_edges.at<float>(ToLevelZeroPixel(point, scale, distance_to_edges.size())) >
           limit;
  });
}

void SuppressNonMaxima(std::vector<cv::KeyPoint>& points, const cv::Size& level_size, int window) {
  if (points.size() < 2) return;
  // Strongest first, so a point survives only if no stronger survivor is inside its window.
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return points[a].response > points[b].response;
  });
  const int radius = window / 2;
  cv::Mat taken(level_size, CV_8UC1, cv::Scalar(0));
  std::vector<cv::KeyPoint> kept;
  kept.reserve(points.size());
  for (const std::size_t index : order) {
    const cv::KeyPoint& point = points[index];
    const int x = std::clamp(cvRound(point.pt.x), 0, level_size.width - 1);
    const int y = std::clamp(cvRound(point.pt.y), 0, level_size.height - 1);
    bool suppressed = false;
    for (int dy = -radius; dy <= radius && !suppressed; ++dy) {
      const int yy = y + dy;
      if (yy < 0 || yy >= level_size.height) continue;
      const uchar* row = taken.ptr<uchar>(yy);
      for (int dx = -radius; dx <= radius; ++dx) {
        const int xx = x + dx;
        if (xx >= 0 && xx < level_size.width && row[xx]) {
          suppressed = true;
          break;
        }
      }
    }
    if (suppressed) continue;
    taken.at<uchar>(y, x) = 1;
    kept.push_back(point);
  }
  points = std::move(kept);
}

}  // namespace noctua::features
