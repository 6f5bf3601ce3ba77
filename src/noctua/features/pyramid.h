#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace noctua::features {

// Grey image pyramid with ORB-SLAM's geometry: level l is the image scaled by 1/scale_factor^l,
// its size rounded, each level resized from the previous one.
class ImagePyramid {
 public:
  ImagePyramid(const cv::Mat& gray, int num_levels, double scale_factor);

  int num_levels() const { return static_cast<int>(levels_.size()); }
  const cv::Mat& level(int l) const { return levels_[static_cast<std::size_t>(l)]; }
  // Multiply level-l pixel coordinates by scale(l) to get level-0 coordinates.
  double scale(int l) const { return scales_[static_cast<std::size_t>(l)]; }

 private:
  std::vector<cv::Mat> levels_;
  std::vector<double> scales_;
};

}  // namespace noctua::features
