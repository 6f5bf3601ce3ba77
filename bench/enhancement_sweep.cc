// Chooses the CLAHE defaults by measurement: for each clip limit and tile grid, the number of
// correct matches between an image and a copy warped by a known homography (rotation 8 degrees,
// scale 0.9, fresh sensor noise), on the real low-light photos and on darkened TUM fr1 frames.
// A match is correct when the warped position of its first point lies within 3 px of its
// partner. Prints a Markdown table.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/features/extractor.h"
#include "noctua/sim/low_light.h"

namespace {

std::vector<cv::Mat> LoadGrey(const std::filesystem::path& dir, std::size_t count,
                              std::size_t step) {
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < paths.size() && images.size() < count; i += step) {
    images.push_back(cv::imread(paths[i].string(), cv::IMREAD_GRAYSCALE));
  }
  return images;
}

cv::Mat AddNoise(const cv::Mat& image, double sigma, unsigned seed) {
  cv::Mat noise(image.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat out;
  image.convertTo(out, CV_32F);
  out += noise;
  out.convertTo(out, CV_8U);
  return out;
}

int CorrectMatches(noctua::features::Extractor& extractor, const cv::Mat& image, unsigned seed) {
  const cv::Point2f centre(static_cast<float>(image.cols) / 2.0f,
                           static_cast<float>(image.rows) / 2.0f);
  cv::Mat affine = cv::getRotationMatrix2D(centre, 8.0, 0.9);
  cv::Mat warped;
  cv::warpAffine(image, warped, affine, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  warped = AddNoise(warped, 1.5, seed);
  const auto a = extractor.Extract(AddNoise(image, 1.5, seed + 1));
  const auto b = extractor.Extract(warped);
  if (a.descriptors.empty() || b.descriptors.empty()) return 0;
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(a.descriptors, b.descriptors, knn, 2);
  int correct = 0;
  for (const auto& pair : knn) {
    if (pair.size() < 2 || pair[0].distance >= 0.8f * pair[1].distance) continue;
    const cv::Point2f p = a.keypoints[static_cast<std::size_t>(pair[0].queryIdx)].pt;
    const cv::Point2f q(
        static_cast<float>(affine.at<double>(0, 0) * p.x + affine.at<double>(0, 1) * p.y +
                           affine.at<double>(0, 2)),
        static_cast<float>(affine.at<double>(1, 0) * p.x + affine.at<double>(1, 1) * p.y +
                           affine.at<double>(1, 2)));
    if (cv::norm(q - b.keypoints[static_cast<std::size_t>(pair[0].trainIdx)].pt) < 3.0) ++correct;
  }
  return correct;
}

}  // namespace

int main() {
  const std::filesystem::path data = std::filesystem::path(NOCTUA_SHARED_DIR) / "data";
  const auto lol = LoadGrey(data / "lowlight" / "lol_low20" / "low", 10, 2);
  std::vector<cv::Mat> fr1_dark;
  for (const auto& frame : LoadGrey(data / "tum_fr1_rpy_200" / "rgb", 10, 20)) {
    // The project's darkening, noiseless: this sweep adds its own fresh noise per copy.
    fr1_dark.push_back(
        noctua::sim::DarkenToLevel(frame, 0.15, noctua::sim::SensorModelByName("noiseless"), 0));
  }
  std::cout << "| enhancement | clip | tiles | correct matches, LOL (mean) | correct matches, fr1 "
               "at 15% (mean) |\n"
               "|---|---:|---:|---:|---:|\n";
  auto evaluate = [&](const noctua::features::ExtractorOptions& options, const std::string& label,
                      const std::string& clip, const std::string& tiles) {
    noctua::features::Extractor extractor(options);
    double lol_sum = 0.0;
    double fr1_sum = 0.0;
    unsigned seed = 1;
    for (const auto& image : lol) lol_sum += CorrectMatches(extractor, image, seed += 2);
    for (const auto& image : fr1_dark) fr1_sum += CorrectMatches(extractor, image, seed += 2);
    std::cout << "| " << label << " | " << clip << " | " << tiles << " | "
              << cv::format("%.0f", lol_sum / static_cast<double>(lol.size())) << " | "
              << cv::format("%.0f", fr1_sum / static_cast<double>(fr1_dark.size())) << " |"
              << std::endl;
  };
  noctua::features::ExtractorOptions options;
  options.dynamic_filter.enabled = options.edge_filter.enabled = options.nms_filter.enabled = false;
  options.enhancement.method = noctua::image::EnhancementMethod::kNone;
  evaluate(options, "none", "-", "-");
  options.enhancement.method = noctua::image::EnhancementMethod::kHistogramEqualization;
  evaluate(options, "he", "-", "-");
  options.enhancement.method = noctua::image::EnhancementMethod::kClahe;
  for (int tiles : {4, 8, 16}) {
    for (double clip : {1.0, 2.0, 3.0, 4.0, 6.0, 8.0}) {
      options.enhancement.clahe_clip_limit = clip;
      options.enhancement.clahe_tiles_x = options.enhancement.clahe_tiles_y = tiles;
      evaluate(options, "clahe", cv::format("%.0f", clip), std::to_string(tiles));
    }
  }
  return 0;
}
