#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace noctua::features {

// A colour per pyramid level (BGR), the same in every overlay so that figures can be compared.
cv::Scalar LevelColour(int octave);

// The image (grey or colour) with each keypoint drawn as a circle of its patch radius and a tick
// for its angle, coloured by pyramid level, and a caption line at the top.
cv::Mat DrawKeypointsByLevel(const cv::Mat& image, const std::vector<cv::KeyPoint>& keypoints,
                             const std::string& caption);

}  // namespace noctua::features
