#include "noctua/image/enhancement.h"

#include "noctua/util/error.h"

namespace noctua::image {

EnhancementMethod ParseEnhancementMethod(const std::string& name) {
  if (name == "none") return EnhancementMethod::kNone;
  if (name == "he") return EnhancementMethod::kHistogramEqualization;
  if (name == "clahe") return EnhancementMethod::kClahe;
  throw Error("unknown enhancement '" + name + "' (expected none, he or clahe)");
}

std::string ToString(EnhancementMethod method) {
  switch (method) {
    case EnhancementMethod::kNone:
      return "none";
    case EnhancementMethod::kHistogramEqualization:
      return "he";
    case EnhancementMethod::kClahe:
      return "clahe";
  }
  return "unknown";
}

void EnhancementOptions::Check() const {
  CheckOption(clahe_clip_limit > 0.0, "enhancement.clahe_clip_limit must be > 0");
  CheckOption(clahe_tiles_x >= 1 && clahe_tiles_x <= 64,
              "enhancement.clahe_tiles_x must be in [1, 64]");
  CheckOption(clahe_tiles_y >= 1 && clahe_tiles_y <= 64,
              "enhancement.clahe_tiles_y must be in [1, 64]");
}

cv::Mat ToGray8U(const cv::Mat& image) {
  if (image.empty()) throw Error("empty image");
  if (image.depth() != CV_8U) {
    throw Error("expected an 8-bit image, got depth " + std::to_string(image.depth()) +
                " (convert 16-bit or float images to 8-bit first)");
  }
  cv::Mat gray;
  switch (image.channels()) {
    case 1:
      return image;
    case 3:
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      return gray;
    case 4:
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
      return gray;
    default:
      throw Error("expected 1, 3 or 4 channels, got " + std::to_string(image.channels()));
  }
}

Enhancer::Enhancer(const EnhancementOptions& options) : options_(options) {
  options_.Check();
  if (options_.method == EnhancementMethod::kClahe) {
    clahe_ = cv::createCLAHE(options_.clahe_clip_limit,
                             cv::Size(options_.clahe_tiles_x, options_.clahe_tiles_y));
  }
}

cv::Mat Enhancer::Apply(const cv::Mat& gray) const {
  CV_Assert(gray.type() == CV_8UC1);
  cv::Mat enhanced;
  switch (options_.method) {
    case EnhancementMethod::kNone:
      return gray;
    case EnhancementMethod::kHistogramEqualization:
      cv::equalizeHist(gray, enhanced);
      break;
    case EnhancementMethod::kClahe:
      clahe_->apply(gray, enhanced);
      break;
  }
  return enhanced;
}

}  // namespace noctua::image
