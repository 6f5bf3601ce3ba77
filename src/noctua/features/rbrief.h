#pragma once

#include <opencv2/features2d.hpp>
#include <vector>

#include "noctua/features/extractor_options.h"
#include "noctua/features/pyramid.h"

namespace noctua::features {

// rBRIEF descriptors (256 bits, 32 bytes, steered by the keypoint angle, sampled on the Gaussian-
// blurred pyramid level) computed by OpenCV's ORB on our keypoints. Using OpenCV's own code keeps
// the learned sampling pattern, the blur and the steering exactly ORB's, so our descriptors can be
// matched against any ORB descriptor.
class RbriefDescriber {
 public:
  explicit RbriefDescriber(const PyramidFastOptions& options);

  // Keypoints in ORB-SLAM semantics (level-0 coordinates, octave, angle) on a pyramid built with
  // the same scale factor. Each level is described on its own, so OpenCV does not rebuild the
  // pyramid. Points too close to a border for a descriptor are removed and the rest are ordered
  // by level, as OpenCV does.
  void Compute(const ImagePyramid& pyramid, std::vector<cv::KeyPoint>& keypoints,
               cv::Mat& descriptors) const;

  // Describes the points of one level (level-0 coordinates, all of octave `level`); points too
  // close to the border are removed. Safe to call for different levels at the same time.
  void ComputeLevel(const ImagePyramid& pyramid, int level, std::vector<cv::KeyPoint>& keypoints,
                    cv::Mat& descriptors) const;

  // The same for keypoints without a pyramid at hand (builds one from `gray`).
  void Compute(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints,
               cv::Mat& descriptors) const;

 private:
  PyramidFastOptions options_;
  // One single-level ORB per pyramid level, so that levels can be described concurrently.
  std::vector<cv::Ptr<cv::ORB>> single_level_orbs_;
};

}  // namespace noctua::features
