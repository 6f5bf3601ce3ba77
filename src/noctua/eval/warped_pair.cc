#include "noctua/eval/warped_pair.h"

#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/eval/match_judge.h"
#include "noctua/features/ofast.h"
#include "noctua/image/noise.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

cv::Mat WithFreshNoise(const cv::Mat& image, double sigma, unsigned seed) {
  if (sigma <= 0.0) return image;
  cv::Mat noise(image.size(), CV_32FC(image.channels()));
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat out;
  image.convertTo(out, CV_32F);
  out += noise;
  out.convertTo(out, CV_8U);  // saturates
  return out;
}

double PhotoNoise(const cv::Mat& photo) {
  cv::Mat grey = photo;
  if (photo.channels() == 3) cv::cvtColor(photo, grey, cv::COLOR_BGR2GRAY);
  return image::EstimateNoiseSigmaAcrossScales(grey);
}

// The same border for every method: none is counted as losing corners where ORB-SLAM's geometry
// keeps none.
void CountRepeated(const std::vector<cv::KeyPoint>& in_photo,
                   const std::vector<cv::KeyPoint>& in_copy, const cv::Mat& affine, cv::Size size,
                   double within_px, WarpedPairResult& result) {
  if (in_photo.empty()) return;
  std::vector<cv::Point2f> points;
  points.reserve(in_photo.size());
  for (const auto& keypoint : in_photo) points.push_back(keypoint.pt);
  std::vector<cv::Point2f> moved;
  cv::transform(points, moved, affine);
  const PointGrid grid(in_copy, size, within_px);
  for (const cv::Point2f& moved_point : moved) {
    const Eigen::Vector2d at(moved_point.x, moved_point.y);
    if (!InsideBorder(at, size, features::kEdgeThreshold)) continue;
    ++result.comparable;
    if (grid.NearestDistance(at) <= within_px) ++result.repeated;
  }
}

}  // namespace

void WarpedPairOptions::Check() const {
  CheckOption(scale > 0.0, "warped pair scale must be positive");
  CheckOption(ratio > 0.0 && ratio <= 1.0, "warped pair ratio must be in (0, 1]");
  CheckOption(correct_px > 0.0, "warped pair correct_px must be positive");
  CheckOption(fresh_noise_multiple >= 0.0, "warped pair fresh_noise_multiple must not be negative");
}

WarpedPairResult MatchWarpedPair(pipeline::FeatureMethod& method, const cv::Mat& photo,
                                 const WarpedPairOptions& options, unsigned seed) {
  options.Check();
  if (photo.empty() || photo.depth() != CV_8U || (photo.channels() != 1 && photo.channels() != 3)) {
    throw Error("warped pair: the photo must be an 8-bit grey or BGR image");
  }
  WarpedPairResult result;
  result.noise_sigma = PhotoNoise(photo);
  const double fresh = options.fresh_noise_multiple * result.noise_sigma;
  const cv::Point2f centre(static_cast<float>(photo.cols) / 2.0f,
                           static_cast<float>(photo.rows) / 2.0f);
  const cv::Mat affine = cv::getRotationMatrix2D(centre, options.rotation_deg, options.scale);
  cv::Mat warped;
  cv::warpAffine(photo, warped, affine, photo.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const features::Extraction a = method.Run(WithFreshNoise(photo, fresh, seed));
  const features::Extraction b = method.Run(WithFreshNoise(warped, fresh, seed + 1));
  result.keypoints = static_cast<int>(a.keypoints.size());
  CountRepeated(a.keypoints, b.keypoints, affine, photo.size(), options.correct_px, result);
  if (a.descriptors.empty() || b.descriptors.empty()) return result;
  const std::vector<cv::DMatch> matches =
      MatchWithRatioTest(a.descriptors, b.descriptors, method.norm_type(), options.ratio);
  result.matches = static_cast<int>(matches.size());
  std::vector<cv::Point2f> points;
  for (const cv::DMatch& match : matches) {
    points.push_back(a.keypoints[static_cast<std::size_t>(match.queryIdx)].pt);
  }
  std::vector<cv::Point2f> moved;
  if (!points.empty()) cv::transform(points, moved, affine);
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const cv::Point2f partner = b.keypoints[static_cast<std::size_t>(matches[k].trainIdx)].pt;
    if (cv::norm(moved[k] - partner) <= options.correct_px) ++result.correct;
  }
  return result;
}

}  // namespace noctua::eval
