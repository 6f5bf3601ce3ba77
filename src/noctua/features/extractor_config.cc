#include "noctua/features/extractor_config.h"

#include <spdlog/spdlog.h>

#include <set>

#include "noctua/io/yaml_file.h"
#include "noctua/util/error.h"

namespace noctua::features {

ExtractorOptions ExtractorOptionsFromYaml(const YAML::Node& root, const std::string& source,
                                          ExtractorOptions defaults) {
  using io::ReadSetting;
  ExtractorOptions options = defaults;
  if (!root.IsDefined() || root.IsNull()) return options;

  ReadSetting(root, "ORBextractor.nFeatures", source, options.fast.num_features);
  ReadSetting(root, "ORBextractor.scaleFactor", source, options.fast.scale_factor);
  ReadSetting(root, "ORBextractor.nLevels", source, options.fast.num_levels);
  ReadSetting(root, "ORBextractor.iniThFAST", source, options.fast.initial_fast_threshold);
  ReadSetting(root, "ORBextractor.minThFAST", source, options.fast.min_fast_threshold);

  const YAML::Node section = root["extractor"];
  if (section.IsDefined() && !section.IsNull()) {
    if (!section.IsMap()) {
      throw Error(source + ":" + std::to_string(section.Mark().line + 1) +
                  ": 'extractor' must be a map of settings");
    }
    static const std::set<std::string> kKnown = {"enhancement",
                                                 "clahe_clip_limit",
                                                 "clahe_tiles_x",
                                                 "clahe_tiles_y",
                                                 "cell_size",
                                                 "dynamic_filter",
                                                 "edge_filter",
                                                 "edge_radius_px",
                                                 "edge_fill",
                                                 "nms_filter",
                                                 "nms_window",
                                                 "descriptors",
                                                 "parallel",
                                                 "noise_target_mean_grey",
                                                 "noise_max_gain",
                                                 "noise_threshold_multiple",
                                                 "noise_max_residual_sigma"};
    for (const auto& entry : section) {
      const auto key = entry.first.as<std::string>();
      if (!kKnown.contains(key)) {
        spdlog::warn("{}:{}: unknown setting 'extractor.{}' is ignored", source,
                     entry.first.Mark().line + 1, key);
      }
    }
    std::string enhancement;
    if (ReadSetting(section, "enhancement", source, enhancement)) {
      try {
        options.enhancement.method = image::ParseEnhancementMethod(enhancement);
      } catch (const Error& error) {
        throw Error(source + ": extractor.enhancement: " + error.what());
      }
    }
    ReadSetting(section, "clahe_clip_limit", source, options.enhancement.clahe_clip_limit);
    ReadSetting(section, "clahe_tiles_x", source, options.enhancement.clahe_tiles_x);
    ReadSetting(section, "clahe_tiles_y", source, options.enhancement.clahe_tiles_y);
    ReadSetting(section, "cell_size", source, options.fast.cell_size);
    ReadSetting(section, "dynamic_filter", source, options.dynamic_filter.enabled);
    ReadSetting(section, "edge_filter", source, options.edge_filter.enabled);
    ReadSetting(section, "edge_radius_px", source, options.edge_filter.radius_px);
    ReadSetting(section, "edge_fill", source, options.edge_filter.fill_to_quota);
    ReadSetting(section, "nms_filter", source, options.nms_filter.enabled);
    ReadSetting(section, "nms_window", source, options.nms_filter.window);
    ReadSetting(section, "descriptors", source, options.compute_descriptors);
    ReadSetting(section, "parallel", source, options.parallel);
    // The noctua method's noise-adaptive stage (on only for that method).
    auto& adaptive = options.noise_adaptive;
    ReadSetting(section, "noise_target_mean_grey", source, adaptive.target_mean_grey);
    ReadSetting(section, "noise_max_gain", source, adaptive.max_gain);
    ReadSetting(section, "noise_threshold_multiple", source, adaptive.threshold_noise_multiple);
    ReadSetting(section, "noise_max_residual_sigma", source, adaptive.max_residual_sigma);
  }
  try {
    options.Check();
  } catch (const Error& error) {
    throw Error(source + ": " + error.what());
  }
  return options;
}

ExtractorOptions LoadExtractorOptions(const std::filesystem::path& path,
                                      ExtractorOptions defaults) {
  return ExtractorOptionsFromYaml(io::LoadYamlFile(path), path.string(), defaults);
}

}  // namespace noctua::features
