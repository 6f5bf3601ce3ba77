// The extractor as a cv::Feature2D on one image: prints how many keypoints it found.
// Usage: extract_keypoints IMAGE
#include <iostream>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "noctua/features/extractor.h"
#include "noctua/util/error.h"
#include "noctua/util/version.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: extract_keypoints IMAGE\n";
    return 1;
  }
  const cv::Mat image = cv::imread(argv[1], cv::IMREAD_COLOR);
  if (image.empty()) {
    std::cerr << "extract_keypoints: cannot read " << argv[1] << "\n";
    return 1;
  }
  try {
    noctua::features::ExtractorOptions options;  // documented defaults
    options.Check();
    cv::Ptr<cv::Feature2D> extractor = noctua::features::Extractor::Create(options);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    extractor->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    std::cout << "noctua " << noctua::Version() << ": " << keypoints.size() << " keypoints, "
              << descriptors.rows << " descriptors of " << descriptors.cols << " bytes\n";
  } catch (const noctua::Error& error) {
    std::cerr << "extract_keypoints: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
