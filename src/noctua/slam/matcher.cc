#include "noctua/slam/matcher.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/features2d.hpp>

namespace noctua::slam {
namespace {

constexpr int kHistogramBins = 30;

// Chi-square bound of one degree of freedom at 95 %: a point's distance to its epipolar line.
constexpr double kChi2OneDof = 3.84;

// Radius multiplier by viewing angle (ORB-SLAM: tighter when seen from the same direction).
double RadiusByViewingCos(double view_cos) { return view_cos > 0.998 ? 2.5 : 4.0; }

}  // namespace

void Matcher::KeepConsistentRotation(const std::vector<float>& angle_changes,
                                     std::vector<int>& matched_indices) const {
  if (!check_orientation_) return;
  std::array<std::vector<std::size_t>, kHistogramBins> bins;
  for (std::size_t k = 0; k < angle_changes.size(); ++k) {
    float change = angle_changes[k];
    if (change < 0.0f) change += 360.0f;
    int bin = static_cast<int>(std::lround(change * kHistogramBins / 360.0f));
    if (bin == kHistogramBins) bin = 0;
    bins[static_cast<std::size_t>(bin)].push_back(k);
  }
  std::array<std::size_t, kHistogramBins> sizes{};
  for (int b = 0; b < kHistogramBins; ++b)
    sizes[static_cast<std::size_t>(b)] = bins[static_cast<std::size_t>(b)].size();
  std::array<int, kHistogramBins> order{};
  for (int b = 0; b < kHistogramBins; ++b) order[static_cast<std::size_t>(b)] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return sizes[static_cast<std::size_t>(a)] > sizes[static_cast<std::size_t>(b)];
  });
  // ORB-SLAM keeps the second and third bins only when they hold at least a tenth of the first.
  const std::size_t top = sizes[static_cast<std::size_t>(order[0])];
  std::vector<bool> keep_bin(kHistogramBins, false);
  keep_bin[static_cast<std::size_t>(order[0])] = true;
  for (int r = 1; r < 3; ++r) {
    if (sizes[static_cast<std::size_t>(order[static_cast<std::size_t>(r)])] * 10 >= top) {
      keep_bin[static_cast<std::size_t>(order[static_cast<std::size_t>(r)])] = true;
    }
  }
  for (int b = 0; b < kHistogramBins; ++b) {
    if (keep_bin[static_cast<std::size_t>(b)]) continue;
    for (std::size_t k : bins[static_cast<std::size_t>(b)]) matched_indices[k] = -1;
  }
}

int Matcher::SearchByProjection(Frame& current, const Frame& last, double radius) const {
  const FrameFeatures& features = *current.features;
  const auto& camera = features.camera();
  std::vector<float> angle_changes;
  std::vector<int> matched;  // index into current per accepted match
  for (int i = 0; i < last.size(); ++i) {
    MapPoint* point = last.map_points[static_cast<std::size_t>(i)];
    if (point == nullptr || point->bad() || last.outlier[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector3d in_camera = current.pose_cw * point->position();
    if (in_camera.z() <= 0.0) continue;
    const Eigen::Vector2d pixel = camera.Project(in_camera);
    if (!features.InBounds(pixel.x(), pixel.y())) continue;
    const double right_x = pixel.x() - bf_ / in_camera.z();
    const int last_octave = last.features->octave(i);
    const double window = radius * pyramid_.scale[static_cast<std::size_t>(last_octave)];
    const auto candidates = features.InArea(pixel.x(), pixel.y(), window,
                                            std::max(0, last_octave - 1), last_octave + 1);
    int best_distance = 256;
    int best_index = -1;
    for (int candidate : candidates) {
      if (current.moving[static_cast<std::size_t>(candidate)]) continue;
      MapPoint* existing = current.map_points[static_cast<std::size_t>(candidate)];
      if (existing != nullptr && existing->num_observations() > 0) continue;
      if (features.depth(candidate) > 0.0 &&
          std::abs(right_x - features.right_u(candidate)) > window) {
        continue;
      }
      const int distance = DescriptorDistance(point->descriptor(), features.descriptor(candidate));
      if (distance < best_distance) {
        best_distance = distance;
        best_index = candidate;
      }
    }
    if (best_distance > kThresholdHigh) continue;
    current.map_points[static_cast<std::size_t>(best_index)] = point;
    matched.push_back(best_index);
    angle_changes.push_back(last.features->keypoint(i).angle - features.keypoint(best_index).angle);
  }
  std::vector<int> kept = matched;
  KeepConsistentRotation(angle_changes, kept);
  int count = 0;
  for (std::size_t k = 0; k < matched.size(); ++k) {
    if (kept[k] < 0) {
      current.map_points[static_cast<std::size_t>(matched[k])] = nullptr;
    } else {
      ++count;
    }
  }
  return count;
}

int Matcher::SearchByProjection(Frame& frame, const std::vector<MapPoint*>& points,
                                double radius) const {
  const FrameFeatures& features = *frame.features;
  int count = 0;
  for (MapPoint* point : points) {
    if (!point->track_in_view || point->bad()) continue;
    const int level = point->track_level;
    const double window = radius * RadiusByViewingCos(point->track_view_cos) *
                          pyramid_.scale[static_cast<std::size_t>(level)];
    const auto candidates =
        features.InArea(point->track_x, point->track_y, window, std::max(0, level - 1), level);
    int best_distance = 256, second_distance = 256;
    int best_level = -1, second_level = -1;
    int best_index = -1;
    for (int candidate : candidates) {
      if (frame.moving[static_cast<std::size_t>(candidate)]) continue;
      MapPoint* existing = frame.map_points[static_cast<std::size_t>(candidate)];
      if (existing != nullptr && existing->num_observations() > 0) continue;
      if (features.depth(candidate) > 0.0 &&
          std::abs(point->track_right_x - features.right_u(candidate)) > window) {
        continue;
      }
      const int distance = DescriptorDistance(point->descriptor(), features.descriptor(candidate));
      if (distance < best_distance) {
        second_distance = best_distance;
        second_level = best_level;
        best_distance = distance;
        best_level = features.octave(candidate);
        best_index = candidate;
      } else if (distance < second_distance) {
        second_distance = distance;
        second_level = features.octave(candidate);
      }
    }
    if (best_distance > kThresholdHigh) continue;
    if (best_level == second_level && best_distance > ratio_ * second_distance) continue;
    frame.map_points[static_cast<std::size_t>(best_index)] = point;
    ++count;
  }
  return count;
}

int Matcher::SearchByProjection(Frame& frame, const KeyFrame& keyframe,
                                const std::vector<MapPoint*>& already, double radius,
                                int max_distance) const {
  const FrameFeatures& features = *frame.features;
  const auto& camera = features.camera();
  const Eigen::Vector3d centre = frame.CameraCentre();
  std::vector<float> angle_changes;
  std::vector<int> matched;
  for (int i = 0; i < keyframe.features().size(); ++i) {
    MapPoint* point = keyframe.map_point(i);
    if (point == nullptr || point->bad()) continue;
    if (std::find(already.begin(), already.end(), point) != already.end()) continue;
    const Eigen::Vector3d in_camera = frame.pose_cw * point->position();
    if (in_camera.z() <= 0.0) continue;
    const Eigen::Vector2d pixel = camera.Project(in_camera);
    if (!features.InBounds(pixel.x(), pixel.y())) continue;
    const double distance_to_centre = (point->position() - centre).norm();
    if (distance_to_centre < point->min_distance() || distance_to_centre > point->max_distance()) {
      continue;
    }
    const int level = point->PredictScale(distance_to_centre, pyramid_);
    const double window = radius * pyramid_.scale[static_cast<std::size_t>(level)];
    const auto candidates =
        features.InArea(pixel.x(), pixel.y(), window, std::max(0, level - 1), level + 1);
    int best_distance = 256;
    int best_index = -1;
    for (int candidate : candidates) {
      if (frame.map_points[static_cast<std::size_t>(candidate)] != nullptr ||
          frame.moving[static_cast<std::size_t>(candidate)]) {
        continue;
      }
      const int distance = DescriptorDistance(point->descriptor(), features.descriptor(candidate));
      if (distance < best_distance) {
        best_distance = distance;
        best_index = candidate;
      }
    }
    if (best_distance > max_distance) continue;
    frame.map_points[static_cast<std::size_t>(best_index)] = point;
    matched.push_back(best_index);
    angle_changes.push_back(keyframe.features().keypoint(i).angle -
                            features.keypoint(best_index).angle);
  }
  std::vector<int> kept = matched;
  KeepConsistentRotation(angle_changes, kept);
  int count = 0;
  for (std::size_t k = 0; k < matched.size(); ++k) {
    if (kept[k] < 0) {
      frame.map_points[static_cast<std::size_t>(matched[k])] = nullptr;
    } else {
      ++count;
    }
  }
  return count;
}

int Matcher::SearchByDescriptor(const KeyFrame& keyframe, const Frame& frame,
                                std::vector<MapPoint*>& matches) const {
  matches.assign(static_cast<std::size_t>(frame.size()), nullptr);
  std::vector<int> keyframe_indices;
  cv::Mat keyframe_descriptors;
  for (int i = 0; i < keyframe.features().size(); ++i) {
    MapPoint* point = keyframe.map_point(i);
    if (point == nullptr || point->bad()) continue;
    keyframe_indices.push_back(i);
    keyframe_descriptors.push_back(keyframe.features().descriptors().row(i));
  }
  if (keyframe_indices.empty() || frame.size() < 2) return 0;
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(keyframe_descriptors, frame.features->descriptors(), knn, 2);
  // Per frame keypoint, the best keyframe point that passed the tests.
  std::vector<int> best_query(static_cast<std::size_t>(frame.size()), -1);
  std::vector<float> best_distance(static_cast<std::size_t>(frame.size()), 1e9f);
  for (std::size_t q = 0; q < knn.size(); ++q) {
    if (knn[q].size() < 2) continue;
    const cv::DMatch& best = knn[q][0];
    if (best.distance > kThresholdLow || best.distance >= ratio_ * knn[q][1].distance) continue;
    const auto train = static_cast<std::size_t>(best.trainIdx);
    if (best.distance < best_distance[train]) {
      best_distance[train] = best.distance;
      best_query[train] = static_cast<int>(q);
    }
  }
  std::vector<int> best_point(static_cast<std::size_t>(frame.size()), -1);
  for (int f = 0; f < frame.size(); ++f) {
    const int q = best_query[static_cast<std::size_t>(f)];
    if (q >= 0)
      best_point[static_cast<std::size_t>(f)] = keyframe_indices[static_cast<std::size_t>(q)];
  }
  return CollectMatches(keyframe, frame, best_point, matches);
}

int Matcher::SearchByFeatureVector(const KeyFrame& keyframe,
                                   const place::FeatureVector& keyframe_features,
                                   const Frame& frame, const place::FeatureVector& frame_features,
                                   std::vector<MapPoint*>& matches) const {
  matches.assign(static_cast<std::size_t>(frame.size()), nullptr);
  std::vector<int> best_point(static_cast<std::size_t>(frame.size()), -1);
  std::vector<int> best_distance(static_cast<std::size_t>(frame.size()), 256);
  const FrameFeatures& features = keyframe.features();
  auto k = keyframe_features.begin();
  auto f = frame_features.begin();
  while (k != keyframe_features.end() && f != frame_features.end()) {
    if (k->first < f->first) {
      ++k;
      continue;
    }
    if (f->first < k->first) {
      ++f;
      continue;
    }
    for (int i : k->second) {
      const MapPoint* point = keyframe.map_point(i);
      if (point == nullptr || point->bad()) continue;
      int best = 256, second = 256, best_index = -1;
      for (int j : f->second) {
        const int distance =
            DescriptorDistance(features.descriptor(i), frame.features->descriptor(j));
        if (distance < best) {
          second = best;
          best = distance;
          best_index = j;
        } else if (distance < second) {
          second = distance;
        }
      }
      if (best_index < 0 || best > kThresholdLow || best >= ratio_ * second) continue;
      const auto at = static_cast<std::size_t>(best_index);
      if (best < best_distance[at]) {
        best_distance[at] = best;
        best_point[at] = i;
      }
    }
    ++k;
    ++f;
  }
  return CollectMatches(keyframe, frame, best_point, matches);
}

int Matcher::CollectMatches(const KeyFrame& keyframe, const Frame& frame,
                            const std::vector<int>& best_point,
                            std::vector<MapPoint*>& matches) const {
  std::vector<int> matched;
  std::vector<float> angle_changes;
  for (int f = 0; f < frame.size(); ++f) {
    const int i = best_point[static_cast<std::size_t>(f)];
    if (i < 0 || frame.moving[static_cast<std::size_t>(f)]) continue;
    matched.push_back(f);
    angle_changes.push_back(keyframe.features().keypoint(i).angle -
                            frame.features->keypoint(f).angle);
  }
  std::vector<int> kept = matched;
  KeepConsistentRotation(angle_changes, kept);
  int count = 0;
  for (std::size_t m = 0; m < matched.size(); ++m) {
    if (kept[m] < 0) continue;
    const int f = matched[m];
    matches[static_cast<std::size_t>(f)] =
        keyframe.map_point(best_point[static_cast<std::size_t>(f)]);
    ++count;
  }
  return count;
}

std::vector<std::pair<int, int>> Matcher::SearchForTriangulation(
    const KeyFrame& first, const KeyFrame& second, const Eigen::Matrix3d& fundamental_21,
    const std::vector<bool>& first_candidate, const std::vector<bool>& second_candidate) const {
  const FrameFeatures& features1 = first.features();
  const FrameFeatures& features2 = second.features();
  // The epipole: the first camera's centre seen from the second.
  const Eigen::Vector3d centre1_in2 = second.pose_cw() * first.CameraCentre();
  const Eigen::Vector2d epipole = features2.camera().Project(centre1_in2);
  const bool epipole_in_front = centre1_in2.z() > 0.0;
  std::vector<int> best_first(static_cast<std::size_t>(features2.size()), -1);
  std::vector<int> best_distance(static_cast<std::size_t>(features2.size()), 256);
  for (int i = 0; i < features1.size(); ++i) {
    if (!first_candidate[static_cast<std::size_t>(i)]) continue;
    const Eigen::Vector3d line = fundamental_21 * features1.undistorted(i).homogeneous();
    const double line_norm2 = line.head<2>().squaredNorm();
    if (line_norm2 <= 0.0) continue;
    const bool depth1 = features1.depth(i) > 0.0;
    int best = 256, second_best = 256, best_index = -1;
    for (int j = 0; j < features2.size(); ++j) {
      if (!second_candidate[static_cast<std::size_t>(j)]) continue;
      const Eigen::Vector2d& x2 = features2.undistorted(j);
      const int level = features2.octave(j);
      const double sigma2 = 1.0 / pyramid_.inverse_sigma2[static_cast<std::size_t>(level)];
      const double along = line.dot(x2.homogeneous());
      if (along * along / line_norm2 >= kChi2OneDof * sigma2) continue;
      if (!depth1 && features2.depth(j) <= 0.0 && epipole_in_front &&
          (x2 - epipole).squaredNorm() < 100.0 * pyramid_.scale[static_cast<std::size_t>(level)]) {
        continue;  // ORB-SLAM: near the epipole, rays from both cameras are nearly parallel
      }
      const int distance = DescriptorDistance(features1.descriptor(i), features2.descriptor(j));
      if (distance < best) {
        second_best = best;
        best = distance;
        best_index = j;
      } else if (distance < second_best) {
        second_best = distance;
      }
    }
    if (best_index < 0 || best > kThresholdLow) continue;
    if (static_cast<double>(best) >= ratio_ * static_cast<double>(second_best)) continue;
    const auto j = static_cast<std::size_t>(best_index);
    if (best < best_distance[j]) {
      best_distance[j] = best;
      best_first[j] = i;
    }
  }
  std::vector<std::pair<int, int>> pairs;
  std::vector<float> angle_changes;
  for (int j = 0; j < features2.size(); ++j) {
    const int i = best_first[static_cast<std::size_t>(j)];
    if (i < 0) continue;
    pairs.emplace_back(i, j);
    angle_changes.push_back(features1.keypoint(i).angle - features2.keypoint(j).angle);
  }
  std::vector<int> kept(pairs.size(), 0);
  KeepConsistentRotation(angle_changes, kept);
  std::vector<std::pair<int, int>> result;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (kept[k] >= 0) result.push_back(pairs[k]);
  }
  std::sort(result.begin(), result.end());
  return result;
}

}  // namespace noctua::slam
