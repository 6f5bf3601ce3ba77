#include "noctua/pipeline/method_config.h"

#include "noctua/dynamic/dynamic_config.h"
#include "noctua/features/extractor_config.h"
#include "noctua/io/yaml_file.h"

namespace noctua::pipeline {

MethodConfig LoadMethodConfig(const std::filesystem::path& settings,
                              const std::string& detector_model) {
  MethodConfig config;
  if (!settings.empty()) {
    config.extractor = features::LoadExtractorOptions(settings);
    const dynamic::DynamicConfig dynamic =
        dynamic::DynamicConfigFromYaml(io::LoadYamlFile(settings), settings);
    config.detector_model = dynamic.model.string();
    config.detector = dynamic.detector;
    config.motion_levels = dynamic.motion_levels;
    config.dynamic_mask = dynamic.mask;
  }
  if (!detector_model.empty()) config.detector_model = detector_model;
  config.Check();
  return config;
}

}  // namespace noctua::pipeline
