#include "noctua/features/rbrief.h"

#include "noctua/features/ofast.h"

namespace noctua::features {

RbriefDescriber::RbriefDescriber(const PyramidFastOptions& options)
    : options_(options),
      single_level_orb_(cv::ORB::create(options.num_features, 1.2f, 1, kEdgeThreshold, 0, 2,
                                        cv::ORB::FAST_SCORE, kPatchSize,
                                        options.initial_fast_threshold)) {}

void RbriefDescriber::Compute(const ImagePyramid& pyramid, std::vector<cv::KeyPoint>& keypoints,
                              cv::Mat& descriptors) const {
  std::vector<std::vector<cv::KeyPoint>> by_level(static_cast<std::size_t>(pyramid.num_levels()));
  for (const auto& point : keypoints) {
    if (point.octave < 0 || point.octave >= pyramid.num_levels()) continue;
    cv::KeyPoint local = point;
    const auto scale = static_cast<float>(pyramid.scale(point.octave));
    local.pt /= scale;
    local.octave = 0;
    by_level[static_cast<std::size_t>(point.octave)].push_back(local);
  }
  std::vector<cv::KeyPoint> described;
  described.reserve(keypoints.size());
  std::vector<cv::Mat> rows;
  for (int l = 0; l < pyramid.num_levels(); ++l) {
    auto& points = by_level[static_cast<std::size_t>(l)];
    if (points.empty()) continue;
    cv::Mat level_descriptors;
    single_level_orb_->compute(pyramid.level(l), points, level_descriptors);
    const auto scale = static_cast<float>(pyramid.scale(l));
    for (auto& point : points) {
      point.pt *= scale;
      point.octave = l;
      described.push_back(point);
    }
    if (!level_descriptors.empty()) rows.push_back(level_descriptors);
  }
  keypoints = std::move(described);
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
