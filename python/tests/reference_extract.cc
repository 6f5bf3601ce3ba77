// Writes the C++ extractor's keypoints and descriptors of one image with cv::FileStorage, for
// python/tests to compare the Python module's output with.
// Usage: python_reference_extract IMAGE METHOD OUT.yml
#include <iostream>
#include <opencv2/core.hpp>

#include "noctua/io/image_file.h"
#include "noctua/pipeline/method.h"
#include "noctua/util/error.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: python_reference_extract IMAGE METHOD OUT.yml\n";
    return 2;
  }
  try {
    const cv::Mat image = noctua::io::ReadImage8U(argv[1]);
    auto method = noctua::pipeline::CreateMethod(argv[2], noctua::pipeline::MethodConfig{});
    const noctua::features::Extraction result = method->Run(image);
    cv::Mat keypoints(static_cast<int>(result.keypoints.size()), 6, CV_32F);
    for (int i = 0; i < keypoints.rows; ++i) {
      const cv::KeyPoint& k = result.keypoints[static_cast<std::size_t>(i)];
      const float row[6] = {k.pt.x,  k.pt.y,     k.size,
                            k.angle, k.response, static_cast<float>(k.octave)};
      for (int c = 0; c < 6; ++c) keypoints.at<float>(i, c) = row[c];
    }
    cv::FileStorage out(argv[3], cv::FileStorage::WRITE);
    out << "keypoints" << keypoints << "descriptors" << result.descriptors;
  } catch (const noctua::Error& error) {
    std::cerr << "python_reference_extract: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
