#pragma once

#include <string>

#include "noctua/image/enhancement.h"

namespace noctua::features {

// oFAST on an image pyramid with ORB-SLAM's semantics and defaults.
struct PyramidFastOptions {
  int num_features = 1000;          // ORBextractor.nFeatures: points kept over all levels
  double scale_factor = 1.2;        // ORBextractor.scaleFactor: scale between pyramid levels
  int num_levels = 8;               // ORBextractor.nLevels
  int initial_fast_threshold = 20;  // ORBextractor.iniThFAST: first try in each grid cell
  int min_fast_threshold = 7;       // ORBextractor.minThFAST: fallback when a cell is empty
  int cell_size = 30;               // grid cell side in pixels of each level

  void Check() const;
};

// Filter (a): points inside the dynamic mask (non-zero pixels) are dropped.
struct DynamicFilterOptions {
  bool enabled = true;
  void Check() const {}
};

// Filter (b): only points within `radius_px` of an edge pixel survive. The radius is in pixels
// of the point's own pyramid level, so coarse levels (whose points are localised less finely)
// get a proportionally wider band in the full-resolution edge map.
//
// fill_to_quota (not in the paper): when the filters leave a pyramid level fewer points than its
// share of num_features, the strongest of the points the edge filter dropped, spread over the
// level like the others, make up the difference. Points on edges always come first, so the fill
// changes nothing on a frame with enough of them; in heavy noise (15% light) PC finds few edges
// and the strict filter starves the tracker (docs/slam.md). Off by default: the paper's method;
// the SLAM presets in config/ turn it on.
struct EdgeFilterOptions {
  bool enabled = true;
  double radius_px = 2.0;
  bool fill_to_quota = false;
  void Check() const;
};

// Filter (c): in every `window` x `window` neighbourhood of a pyramid level only the point with
// the strongest FAST response survives (the paper uses 3).
struct NmsFilterOptions {
  bool enabled = true;
  int window = 3;
  void Check() const;
};

// Noise-adaptive extraction (the `noctua` method; not in the paper). A frame the camera could not
// expose is brought by one gain to the edge of normal exposure, its pixel noise is measured,
// smoothed down to max_residual_sigma when above it, and FAST's thresholds are raised to
// threshold_noise_multiple x the noise left (features/noise_adaptive.h). A frame exposed
// normally is left exactly as ORB-SLAM's extractor sees it: its noise is small against its
// contrast, ORB's thresholds were made for it, and a noise estimate there mostly measures texture.
struct NoiseAdaptiveOptions {
  bool enabled = false;
  // Frames darker than this mean grey are underexposed; the gain brings them up to it. Lifting
  // them further, to auto-exposure's mid-grey (118), lost frames on the small-pixel JPEG camera
  // model where this did not (docs/extractor.md).
  double target_mean_grey = image::kUnderexposedMeanGrey;
  // The most light the gain makes up for (1/16).
  double max_gain = 16.0;
  // A FAST comparison subtracts two noisy pixels (deviation sqrt(2) sigma); 3 deviations of that
  // difference make a chance pass by noise rare (0.1 %), 9 contiguous ones on the ring rarer still.
  double threshold_noise_multiple = 3.0 * 1.41421356;
  // Noise (grey levels, after the gain) above which the frame is smoothed down to it before FAST;
  // 0: never. 2 keeps FAST's minimum threshold (7) above 3 deviations of a pixel difference
  // (3 sqrt(2) x 2 = 8.5, the floor then rules): with no smoothing the thresholds that noise
  // forces leave too few corners and frames were lost; smoothing to 1 blurred the corners away.
  double max_residual_sigma = 2.0;
  void Check() const;
};

// Everything the extractor does, stage by stage. Switching stages off gives the baselines:
// ORB (no enhancement, no filters), HE-ORB, CLAHE-ORB, and the paper's method (all on).
struct ExtractorOptions {
  image::EnhancementOptions enhancement;
  NoiseAdaptiveOptions noise_adaptive;
  PyramidFastOptions fast;
  DynamicFilterOptions dynamic_filter;
  EdgeFilterOptions edge_filter;
  NmsFilterOptions nms_filter;
  bool compute_descriptors = true;  // false: keypoints only (the FAST baseline)
  // Pyramid levels on OpenCV's thread pool, edge map and dynamic mask on their own threads.
  // Results are identical either way; false keeps everything on the calling thread.
  bool parallel = true;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

}  // namespace noctua::features
