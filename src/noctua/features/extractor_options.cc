#include "noctua/features/extractor_options.h"

#include "noctua/util/error.h"

namespace noctua::features {

void PyramidFastOptions::Check() const {
  CheckOption(num_features >= 1, "ORBextractor.nFeatures must be >= 1");
  CheckOption(scale_factor > 1.0 && scale_factor <= 4.0,
              "ORBextractor.scaleFactor must be in (1, 4]");
  CheckOption(num_levels >= 1 && num_levels <= 32, "ORBextractor.nLevels must be in [1, 32]");
  CheckOption(initial_fast_threshold >= 1 && initial_fast_threshold <= 254,
              "ORBextractor.iniThFAST must be in [1, 254]");
  CheckOption(min_fast_threshold >= 1 && min_fast_threshold <= initial_fast_threshold,
              "ORBextractor.minThFAST must be in [1, iniThFAST]");
  CheckOption(cell_size >= 8, "cell_size must be >= 8");
}

void EdgeFilterOptions::Check() const {
  CheckOption(radius_px >= 0.0 && radius_px <= 50.0, "edge_filter.radius_px must be in [0, 50]");
}

void NmsFilterOptions::Check() const {
  CheckOption(window >= 3 && window % 2 == 1 && window <= 31,
              "nms_filter.window must be odd and in [3, 31]");
}

void NoiseAdaptiveOptions::Check() const {
  if (!(target_mean_grey > 0.0 && target_mean_grey < 255.0)) {
    throw Error("noise_adaptive.target_mean_grey must be in (0, 255)");
  }
  if (!(max_gain >= 1.0)) throw Error("noise_adaptive.max_gain must be at least 1");
  if (!(threshold_noise_multiple >= 0.0)) {
    throw Error("noise_adaptive.threshold_noise_multiple must not be negative");
  }
  if (!(max_residual_sigma >= 0.0)) {
    throw Error("noise_adaptive.max_residual_sigma must not be negative (0: never smooth)");
  }
}

void ExtractorOptions::Check() const {
  enhancement.Check();
  noise_adaptive.Check();
  fast.Check();
  dynamic_filter.Check();
  edge_filter.Check();
  nms_filter.Check();
}

}  // namespace noctua::features
