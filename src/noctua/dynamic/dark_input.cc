#include "noctua/dynamic/dark_input.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "noctua/dynamic/detector.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {

const std::vector<std::pair<DarkEnhancement, std::string>>& DarkEnhancementNames() {
  static const std::vector<std::pair<DarkEnhancement, std::string>> names = {
      {DarkEnhancement::kGain, "gain"},
      {DarkEnhancement::kGamma, "gamma"},
      {DarkEnhancement::kSmoothGain, "smooth-gain"}};
  return names;
}

std::string ToString(DarkEnhancement method) {
  for (const auto& [value, name] : DarkEnhancementNames()) {
    if (value == method) return name;
  }
  return "unknown";
}

DarkEnhancement ParseDarkEnhancement(const std::string& name) {
  std::string known;
  for (const auto& [value, known_name] : DarkEnhancementNames()) {
    if (known_name == name) return value;
    known += (known.empty() ? "" : ", ") + known_name;
  }
  throw Error("unknown dark enhancement '" + name + "' (known: " + known + ")");
}

void DarkInputOptions::Check() const {
  CheckOption(dark_mean_grey >= 0.0 && dark_mean_grey < 255.0,
              "dark input dark_mean_grey must be in [0, 255)");
  CheckOption(target_mean_grey > dark_mean_grey && target_mean_grey < 255.0,
              "dark input target_mean_grey must be above dark_mean_grey and below 255");
  CheckOption(smooth_sigma_px > 0.0 && smooth_sigma_px <= 10.0,
              "dark input smooth_sigma_px must be in (0, 10]");
}

double MeanGrey(const cv::Mat& image8u) {
  if (image8u.empty() || image8u.depth() != CV_8U) {
    throw Error("mean grey needs an 8-bit image");
  }
  cv::Mat colour = image8u;
  if (image8u.channels() == 4) cv::cvtColor(image8u, colour, cv::COLOR_BGRA2BGR);
  return cv::mean(colour.reshape(1))[0];
}

bool IsDark(const cv::Mat& image8u, const DarkInputOptions& options) {
  return MeanGrey(image8u) < options.dark_mean_grey;
}

cv::Mat BrightenForDetection(const cv::Mat& image8u, const DarkInputOptions& options) {
  options.Check();
  const double mean = MeanGrey(image8u);
  if (mean < 0.5) return image8u.clone();
  cv::Mat table(1, 256, CV_8U);
  // The gamma exponent is fitted to the mean of the values, not to the mean value, which is
  // close enough for a target that is only "a normal exposure".
  const double exponent = std::log(options.target_mean_grey / 255.0) / std::log(mean / 255.0);
  const double gain = options.target_mean_grey / mean;
  for (int v = 0; v < 256; ++v) {
    const double out = options.method == DarkEnhancement::kGamma
                           ? 255.0 * std::pow(v / 255.0, exponent)
                           : gain * v;
    table.at<uchar>(v) = cv::saturate_cast<uchar>(std::lround(out));
  }
  cv::Mat out;
  if (options.method == DarkEnhancement::kSmoothGain) {
    cv::GaussianBlur(image8u, out, cv::Size(), options.smooth_sigma_px);
    cv::LUT(out, table, out);
  } else {
    cv::LUT(image8u, table, out);
  }
  if (image8u.channels() == 4) cv::mixChannels(image8u, out, {3, 3});
  return out;
}

namespace {

class DarkAwareDetector : public Detector {
 public:
  DarkAwareDetector(std::unique_ptr<Detector> inner, const DarkInputOptions& options)
      : inner_(std::move(inner)), options_(options) {}

  std::vector<Detection> Detect(const cv::Mat& image) override {
    if (!options_.enabled || !IsDark(image, options_)) return inner_->Detect(image);
    return inner_->Detect(BrightenForDetection(image, options_));
  }
  ModelKind kind() const override { return inner_->kind(); }
  bool has_masks() const override { return inner_->has_masks(); }
  const DetectorOptions& options() const override { return inner_->options(); }

 private:
  std::unique_ptr<Detector> inner_;
  DarkInputOptions options_;
};

}  // namespace

std::unique_ptr<Detector> MakeDarkAwareDetector(std::unique_ptr<Detector> inner,
                                                const DarkInputOptions& options) {
  options.Check();
  return std::make_unique<DarkAwareDetector>(std::move(inner), options);
}

}  // namespace noctua::dynamic
