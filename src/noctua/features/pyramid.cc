#include "noctua/features/pyramid.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace noctua::features {

ImagePyramid::ImagePyramid(const cv::Mat& gray, int num_levels, double scale_factor) {
  CV_Assert(gray.type() == CV_8UC1 && num_levels >= 1);
  levels_.reserve(static_cast<std::size_t>(num_levels));
  scales_.reserve(static_cast<std::size_t>(num_levels));
  for (int l = 0; l < num_levels; ++l) {
    const double scale = std::pow(scale_factor, l);
    if (l == 0) {
      levels_.push_back(gray);
      scales_.push_back(scale);
      continue;
    }
    const cv::Size size(static_cast<int>(std::lround(gray.cols / scale)),
                        static_cast<int>(std::lround(gray.rows / scale)));
    // A level that rounds to nothing ends the pyramid early rather than failing.
    if (size.width < 1 || size.height < 1) break;
    scales_.push_back(scale);
    cv::Mat resized;
    cv::resize(levels_.back(), resized, size, 0, 0, cv::INTER_LINEAR_EXACT);
    levels_.push_back(resized);
  }
}

}  // namespace noctua::features
