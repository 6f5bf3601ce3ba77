#pragma once

#include <opencv2/core.hpp>

#include "noctua/pipeline/method.h"

namespace noctua::eval {

// Matching on single photos, where there is no second view: a photo against a copy warped by a
// known similarity, so that every match can be judged exactly.
struct WarpedPairOptions {
  double rotation_deg = 8.0;
  double scale = 0.9;
  double ratio = 0.8;       // Lowe's ratio test
  double correct_px = 3.0;  // a match is correct when the warp maps its point this close
  // Both copies of a photo carry the same real noise, which would repeat like texture, so each gets
  // fresh Gaussian noise of the photo's own estimated deviation
  // (image::EstimateNoiseSigmaAcrossScales) times this: at 1, at least half of each copy's noise
  // is its own. 0: none.
  double fresh_noise_multiple = 1.0;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

struct WarpedPairResult {
  int keypoints = 0;  // in the photo
  int matches = 0;    // kept by the ratio test
  int correct = 0;
  // Whatever the descriptors say: the photo's points that the warp maps into the copy, at least
  // kEdgeThreshold inside it, and of those the ones the copy detected within correct_px.
  int comparable = 0;
  int repeated = 0;
  double noise_sigma = 0.0;  // the photo's estimated noise, grey levels
};

// `method` on the photo (8-bit BGR or grey) and on its warped copy; the fresh noise of the two
// copies is drawn from `seed` and `seed + 1`. Throws noctua::Error for an empty or non-8-bit photo.
WarpedPairResult MatchWarpedPair(pipeline::FeatureMethod& method, const cv::Mat& photo,
                                 const WarpedPairOptions& options, unsigned seed);

}  // namespace noctua::eval
