#include "noctua/eval/warped_pair.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

// Random grey blocks of several sizes: corners everywhere, no repeated pattern.
cv::Mat BlockTexture(unsigned seed) {
  cv::Mat image(400, 600, CV_8UC1, cv::Scalar(128));
  cv::RNG rng(seed);
  for (int k = 0; k < 600; ++k) {
    const int x = rng.uniform(0, 580);
    const int y = rng.uniform(0, 380);
    const int w = rng.uniform(6, 40);
    const int h = rng.uniform(6, 40);
    cv::rectangle(image, cv::Rect(x, y, w, h), cv::Scalar(rng.uniform(0, 256)), cv::FILLED);
  }
  cv::GaussianBlur(image, image, cv::Size(), 0.8);
  return image;
}

TEST(WarpedPair, MatchesOnATexturedImageAreJudgedCorrect) {
  auto orb = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  const WarpedPairResult result = MatchWarpedPair(*orb, BlockTexture(3), WarpedPairOptions(), 1);
  EXPECT_GT(result.keypoints, 500);
  EXPECT_GT(result.correct, 150);
  // Wrong matches exist (the ratio test is not perfect) but are few on a clean texture.
  EXPECT_GT(result.correct, 0.9 * result.matches);
  EXPECT_LT(result.noise_sigma, 1.0);  // blurred blocks: no noise to speak of
  // Block corners survive a small similarity: most are found again, and every correct match is
  // a corner found again.
  EXPECT_GT(result.comparable, 0.6 * result.keypoints);
  EXPECT_GT(result.repeated, 0.6 * result.comparable);
  EXPECT_GE(result.repeated, result.correct);
}

TEST(WarpedPair, SharedNoiseWouldRepeatLikeTexture) {
  // A noisy photo: without fresh noise both copies carry the same noise, whose corners then match
  // as if they were the scene's; with it, fewer matches survive and the noise is measured.
  cv::Mat noisy = BlockTexture(4);
  cv::Mat noise(noisy.size(), CV_8SC1);
  cv::randn(noise, 0, 12);
  cv::add(noisy, noise, noisy, cv::noArray(), CV_8U);
  auto orb = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  WarpedPairOptions options;
  options.fresh_noise_multiple = 0.0;
  const WarpedPairResult shared = MatchWarpedPair(*orb, noisy, options, 1);
  options.fresh_noise_multiple = 1.0;
  const WarpedPairResult fresh = MatchWarpedPair(*orb, noisy, options, 1);
  EXPECT_GT(fresh.noise_sigma, 6.0);
  EXPECT_GT(shared.correct, fresh.correct);
  EXPECT_GT(fresh.correct, 0);
  // Corners of the shared noise repeat too; fresh noise finds fewer of them again.
  EXPECT_GT(static_cast<double>(shared.repeated) / shared.comparable,
            static_cast<double>(fresh.repeated) / fresh.comparable);
}

TEST(WarpedPair, FlatAndBadPhotos) {
  auto orb = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  WarpedPairOptions options;
  options.fresh_noise_multiple = 0.0;
  const WarpedPairResult flat =
      MatchWarpedPair(*orb, cv::Mat(400, 600, CV_8UC1, cv::Scalar(90)), options, 1);
  EXPECT_EQ(flat.keypoints, 0);
  EXPECT_EQ(flat.matches, 0);
  EXPECT_EQ(flat.comparable, 0);
  EXPECT_THROW(MatchWarpedPair(*orb, cv::Mat(), options, 1), Error);
  EXPECT_THROW(MatchWarpedPair(*orb, cv::Mat(40, 60, CV_16UC1), options, 1), Error);
  options.scale = 0.0;
  EXPECT_THROW(MatchWarpedPair(*orb, BlockTexture(1), options, 1), Error);
}

// Real dark photos (LOL, mean grey about 20): the noise-adaptive method keeps more correct matches
// than plain ORB-SLAM extraction (measured 328 against 219 per photo over the 20,
// bench/dark_photos), and its extra points are corners found again, not noise: it repeats as
// often (0.77 of its points within 3 px, as orb) with half as many points again.
TEST(WarpedPair, NoctuaMatchesMoreThanOrbOnRealDarkPhotos) {
  const auto dir = testing::DataDir() / "lowlight" / "lol_low20" / "low";
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  ASSERT_EQ(paths.size(), 20u);
  auto orb = pipeline::CreateMethod("orb", pipeline::MethodConfig());
  auto noctua = pipeline::CreateMethod("noctua", pipeline::MethodConfig());
  WarpedPairResult orb_sum;
  WarpedPairResult noctua_sum;
  auto add = [](WarpedPairResult& sum, const WarpedPairResult& pair) {
    sum.keypoints += pair.keypoints;
    sum.correct += pair.correct;
    sum.comparable += pair.comparable;
    sum.repeated += pair.repeated;
  };
  unsigned seed = 1;
  for (const auto& path : paths) {
    const cv::Mat photo = testing::ReadImageOrThrow(path, cv::IMREAD_COLOR);
    add(orb_sum, MatchWarpedPair(*orb, photo, WarpedPairOptions(), seed));
    add(noctua_sum, MatchWarpedPair(*noctua, photo, WarpedPairOptions(), seed));
    seed += 2;
  }
  EXPECT_GT(noctua_sum.correct, 1.2 * orb_sum.correct)
      << noctua_sum.correct << " against " << orb_sum.correct;
  EXPECT_GT(noctua_sum.keypoints, 1.3 * orb_sum.keypoints);
  const double orb_repeatability = static_cast<double>(orb_sum.repeated) / orb_sum.comparable;
  const double noctua_repeatability =
      static_cast<double>(noctua_sum.repeated) / noctua_sum.comparable;
  EXPECT_GT(noctua_repeatability, 0.9 * orb_repeatability)
      << noctua_repeatability << " against " << orb_repeatability;
}

}  // namespace
}  // namespace noctua::eval
