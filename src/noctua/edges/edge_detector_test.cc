#include "noctua/edges/edge_detector.h"

#include <gtest/gtest.h>

#include <iostream>
#include <opencv2/imgproc.hpp>

#include "noctua/image/enhancement.h"
#include "noctua/testing/shared_data.h"
#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

cv::Mat Fr1Gray(int index) {
  const auto paths = noctua::testing::Fr1RgbPaths(index + 1);
  return image::ToGray8U(noctua::testing::ReadImageOrThrow(paths.back(), cv::IMREAD_COLOR));
}

EdgeDetector Detector(EdgeMethod method) {
  EdgeDetectorOptions options;
  options.method = method;
  return EdgeDetector(options);
}

// Smooth illumination falling from full to 35% across the frame (a lamp at one side).
cv::Mat Shaded(const cv::Mat& gray) {
  cv::Mat light(gray.size(), CV_32F);
  for (int c = 0; c < gray.cols; ++c) {
    light.col(c).setTo(1.0f - 0.65f * static_cast<float>(gray.cols - 1 - c) /
                                  static_cast<float>(gray.cols - 1));
  }
  cv::Mat value;
  gray.convertTo(value, CV_32F);
  cv::Mat result;
  cv::Mat(value.mul(light)).convertTo(result, CV_8U);
  return result;
}

TEST(EdgeDetector, FastVariantAgreesWithTheReferenceOnRealAndDarkenedFrames) {
  const EdgeDetector reference = Detector(EdgeMethod::kPhaseCongruency);
  // Both places the fast map can be thinned, each with its own thresholds.
  EdgeDetectorOptions full_size;
  full_size.fast_full_size_nms = true;
  full_size.fast_thresholds = {0.2, 0.3};
  const EdgeDetector working_size_fast = Detector(EdgeMethod::kPhaseCongruencyFast);
  const EdgeDetector full_size_fast(full_size);
  double sum[2] = {0.0, 0.0};
  int count = 0;
  for (int index : {0, 100, 199}) {
    const cv::Mat normal = Fr1Gray(index);
    for (double brightness : {1.0, 0.2}) {
      const cv::Mat gray = noctua::testing::ScaleBrightness(normal, brightness);
      const cv::Mat expected = reference.Detect(gray);
      for (int full = 0; full < 2; ++full) {
        const EdgeDetector& fast = full == 1 ? full_size_fast : working_size_fast;
        const EdgeAgreement agreement = CompareEdgeMaps(fast.Detect(gray), expected, 1);
        std::cout << (full == 1 ? "full-size" : "working-size") << " NMS, fr1 frame " << index
                  << " brightness " << brightness << ": F = " << agreement.f_measure << " (P "
                  << agreement.precision << ", R " << agreement.recall << ")\n";
        // Measured 0.67-0.78 per frame (docs/edges.md): the reference itself agrees with its
        // own map at F 0.69-0.87 on darkened frames when one grey level of noise is added, so
        // 0.9 is out of reach for any variant on these frames; the bound guards the measured
        // level.
        EXPECT_GT(agreement.f_measure, 0.62)
            << "frame " << index << " brightness " << brightness << " full size " << full;
        sum[full] += agreement.f_measure;
      }
      ++count;
    }
  }
  EXPECT_GT(sum[0] / count, 0.7);
  EXPECT_GT(sum[1] / count, 0.7);
}

TEST(EdgeDetector, PcEdgesSurviveDarkeningAndShadingFarBetterThanCanny) {
  for (EdgeMethod pc_method : {EdgeMethod::kPhaseCongruency, EdgeMethod::kPhaseCongruencyFast}) {
    const EdgeDetector pc = Detector(pc_method);
    const EdgeDetector canny = Detector(EdgeMethod::kCanny);
    for (int index : {0, 100}) {
      const cv::Mat gray = Fr1Gray(index);
      const cv::Mat pc_map = pc.Detect(gray);
      const cv::Mat canny_map = canny.Detect(gray);
      const cv::Mat dark = noctua::testing::ScaleBrightness(gray, 0.2);
      const double pc_dark = CompareEdgeMaps(pc.Detect(dark), pc_map).f_measure;
      const double canny_dark = CompareEdgeMaps(canny.Detect(dark), canny_map).f_measure;
      const double pc_shaded = CompareEdgeMaps(pc.Detect(Shaded(gray)), pc_map).f_measure;
      const double canny_shaded = CompareEdgeMaps(canny.Detect(Shaded(gray)), canny_map).f_measure;
      std::cout << ToString(pc_method) << " frame " << index << ": x0.2 F " << pc_dark
                << " vs canny " << canny_dark << "; shading F " << pc_shaded << " vs canny "
                << canny_shaded << "\n";
      // Measured: x0.2 PC 0.94-0.98, Canny 0.00; shading PC 0.92-0.94, Canny 0.73-0.83.
      EXPECT_GT(pc_dark, 0.85);
      EXPECT_GT(pc_dark, canny_dark + 0.5);
      EXPECT_GT(pc_shaded, 0.85);
      EXPECT_GT(pc_shaded, canny_shaded + 0.05);
    }
  }
}

TEST(EdgeDetector, PureNoiseGivesAlmostNoPcEdgesThanksToTheNoiseThreshold) {
  cv::Mat noise(240, 320, CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 128.0, 20.0);
  cv::Mat image;
  noise.convertTo(image, CV_8U);
  const int pixels = static_cast<int>(image.total());
  for (EdgeMethod method : {EdgeMethod::kPhaseCongruency, EdgeMethod::kPhaseCongruencyFast}) {
    EdgeDetectorOptions options;
    options.method = method;
    EXPECT_LT(cv::countNonZero(EdgeDetector(options).Detect(image)), pixels / 1000)
        << ToString(method);
    // Without the noise threshold the same noise is full of "edges": the threshold does it.
    options.reference.fixed_noise_threshold = 0.0;
    options.fast.fixed_noise_threshold = 0.0;
    EXPECT_GT(cv::countNonZero(EdgeDetector(options).Detect(image)), pixels / 50)
        << ToString(method);
  }
  // A gradient detector at a fixed threshold marks a large part of the noise.
  EXPECT_GT(cv::countNonZero(Detector(EdgeMethod::kSobel).Detect(image)), pixels / 20);
}

TEST(EdgeDetector, EveryMethodGivesAnEdgeMapOfTheFrame) {
  const cv::Mat colour =
      noctua::testing::ReadImageOrThrow(noctua::testing::Fr1RgbPaths(1).front(), cv::IMREAD_COLOR);
  for (EdgeMethod method : AllEdgeMethods()) {
    const cv::Mat edges = Detector(method).Detect(colour);
    ASSERT_EQ(edges.type(), CV_8U) << ToString(method);
    ASSERT_EQ(edges.size(), colour.size()) << ToString(method);
    const double fraction = cv::countNonZero(edges) / static_cast<double>(edges.total());
    // A desk scene: some edges, far from all pixels.
    EXPECT_GT(fraction, 0.005) << ToString(method);
    EXPECT_LT(fraction, 0.15) << ToString(method);
  }
  EXPECT_THROW(Detector(EdgeMethod::kPhaseCongruencyFast).Detect(cv::Mat()), Error);
  EXPECT_THROW(Detector(EdgeMethod::kPhaseCongruencyFast).Detect(cv::Mat(20, 20, CV_8U)), Error);
}

TEST(EdgeDetector, EdgeMapSourceServesTheExtractor) {
  std::shared_ptr<const EdgeDetector> detector =
      CreateEdgeDetector(EdgeDetectorOptions());  // pc-fast by default
  const auto source = MakeEdgeMapSource(detector);
  const cv::Mat gray = Fr1Gray(0);
  const cv::Mat first = source(gray);
  EXPECT_EQ(first.type(), CV_8U);
  EXPECT_EQ(first.size(), gray.size());
  EXPECT_EQ(cv::norm(first, source(gray), cv::NORM_INF), 0.0);
  EXPECT_THROW(MakeEdgeMapSource(nullptr), Error);
}

TEST(EdgeMapFromPhaseCongruency, EqualsHysteresisOfNmsOnARealFrame) {
  // The edge map fuses the two steps for speed; it must give exactly their composition.
  const FastPhaseCongruency fast{FastPhaseCongruencyOptions()};
  const PhaseCongruency pc = fast.Compute(Fr1Gray(50));
  for (const EdgeMapOptions& options : {EdgeMapOptions{}, EdgeMapOptions{0.2, 0.3}}) {
    const cv::Mat fused = EdgeMapFromPhaseCongruency(pc, options);
    const cv::Mat composed = HysteresisThreshold(
        NonMaximumSuppression(pc.max_moment, pc.orientation, options.low_threshold),
        options.low_threshold, options.high_threshold);
    EXPECT_GT(cv::countNonZero(fused), 1000);
    EXPECT_EQ(cv::norm(fused, composed, cv::NORM_L1), 0.0);
  }
}

TEST(EdgeMethod, NamesRoundTrip) {
  for (EdgeMethod method : AllEdgeMethods()) EXPECT_EQ(ParseEdgeMethod(ToString(method)), method);
  EXPECT_EQ(ParseEdgeMethod("pc-fast"), EdgeMethod::kPhaseCongruencyFast);
  EXPECT_THROW(ParseEdgeMethod("laplace"), Error);
  EdgeDetectorOptions options;
  options.fast_thresholds.high_threshold = 2.0;
  EXPECT_THROW(EdgeDetector{options}, Error);
}

}  // namespace
}  // namespace noctua::edges
