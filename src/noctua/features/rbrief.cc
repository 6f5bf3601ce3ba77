#include "noctua/features/rbrief.h"

#include "noctua/features/ofast.h"

namespace noctua::features {

RbriefDescriber::RbriefDescriber(const PyramidFastOptions& options) : options_(options) {
  for (int l = 0; l < options.num_levels; ++l) {
    single_level_orbs_.push_back(cv::ORB::create(options.num_features, 1.2f, 1, kEdgeThreshold, 0,
                                                 2, cv::ORB::FAST_SCORE, kPatchSize,
                                                 options.initial_fast_threshold));
  }
}

void RbriefDescriber::ComputeLevel(const ImagePyramid& pyramid, int level,
                                   std::vector<cv::KeyPoint>& keypoints,
                                   cv::Mat& descriptors) const {
  if (keypoints.empty()) {
    descriptors = cv::Mat(0, 32, CV_8UC1);
    return;
  }
  // OpenCV describes level-local points of octave 0 on the level image we give it.
  const auto scale = static_cast<float>(pyramid.scale(level));
  for (auto& point : keypoints) {
    point.pt /= scale;
    point.octave = 0;
  }
  const std::size_t engine =
      std::min(static_cast<std::size_t>(level), single_level_orbs_.size() - 1);
  single_level_orbs_[engine]->compute(pyramid.level(level), keypoints, descriptors);
  for (auto& point : keypoints) {
    point.pt *= scale;
    point.octave = level;
  }
  if (descriptors.empty()) descriptors = cv::Mat(0, 32, CV_8UC1);
}

void RbriefDescriber::Compute(const ImagePyramid& pyramid, std::vector<cv::KeyPoint>& keypoints,
                              cv::Mat& descriptors) const {
  std::vector<std::vector<cv::KeyPoint>> by_level(static_cast<std::size_t>(pyramid.num_levels()));
  for (const auto& point : keypoints) {
    if (point.octave >= 0 && point.octave < pyramid.num_levels()) {
      by_level[static_cast<std::size_t>(point.octave)].push_back(point);
    }
  }
  keypoints.clear();
  std::vector<cv::Mat> rows;
  for (int l = 0; l < pyramid.num_levels(); ++l) {
    auto& points = by_level[static_cast<std::size_t>(l)];
    cv::Mat level_descriptors;
    ComputeLevel(pyramid, l, points, level_descriptors);
    keypoints.insert(keypoints.end(), points.begin(), points.end());
    if (!level_descriptors.empty()) rows.push_back(level_descriptors);
  }
  if (rows.empty()) {
    descriptors = cv::Mat(0, 32, CV_8UC1);
  } else {
    cv::vconcat(rows, descriptors);
  }
}

void RbriefDescriber::Compute(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints,
                              cv::Mat& descriptors) const {
  int levels = 1;
  for (const auto& point : keypoints) levels = std::max(levels, point.octave + 1);
  const ImagePyramid pyramid(gray, levels, options_.scale_factor);
  Compute(pyramid, keypoints, descriptors);
}

}  // namespace noctua::features
