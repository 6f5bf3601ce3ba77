#include "noctua/features/rbrief.h"

#include "noctua/features/ofast.h"

namespace noctua::features {

RbriefDescriber::RbriefDescriber(const PyramidFastOptions& options)
    : orb_(cv::ORB::create(options.num_features, static_cast<float>(options.scale_factor),
                           options.num_levels, kEdgeThreshold, 0, 2, cv::ORB::FAST_SCORE,
                           kPatchSize, options.initial_fast_threshold)) {}

void RbriefDescriber::Compute(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints,
                              cv::Mat& descriptors) const {
  if (keypoints.empty()) {
    descriptors = cv::Mat(0, 32, CV_8UC1);
    return;
  }
  orb_->compute(gray, keypoints, descriptors);
  if (descriptors.empty()) descriptors = cv::Mat(0, 32, CV_8UC1);
}

}  // namespace noctua::features
