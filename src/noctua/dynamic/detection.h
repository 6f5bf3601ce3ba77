#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace noctua::dynamic {

// One object found in an image, in that image's pixels.
struct Detection {
  cv::Rect2f box;    // x, y, width, height, clipped to the image
  int class_id = 0;  // COCO class id
  float score = 0.0f;
  // CV_8U, the image's size, 255 on the object: only from segmentation models (else empty).
  cv::Mat mask;
};

// Intersection over union of two boxes; 0 when either is empty.
float IoU(const cv::Rect2f& a, const cv::Rect2f& b);

}  // namespace noctua::dynamic
