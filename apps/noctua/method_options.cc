#include "method_options.h"

#include "noctua/dynamic/dynamic_config.h"
#include "noctua/features/extractor_config.h"
#include "noctua/io/yaml_file.h"

namespace noctua::app {

void AddMethodFlags(CLI::App& command, MethodFlags& flags) {
  std::string names;
  for (const auto& name : pipeline::MethodNames()) names += (names.empty() ? "" : ", ") + name;
  command.add_option("-m,--method", flags.method, "Feature method: " + names)
      ->capture_default_str();
  command.add_option("-c,--config", flags.config,
                     "Settings file (YAML; ORB-SLAM2/3 ORBextractor.* keys and an extractor: map)");
  command.add_option("--detector", flags.detector_model,
                     "ONNX detector (YOLOv8n / YOLOv8n-seg / YOLOX-nano) for the dynamic regions");
}

pipeline::MethodConfig MethodConfigFromFlags(const MethodFlags& flags) {
  pipeline::MethodConfig config;
  if (!flags.config.empty()) {
    config.extractor = features::LoadExtractorOptions(flags.config);
    const dynamic::DynamicConfig dynamic =
        dynamic::DynamicConfigFromYaml(io::LoadYamlFile(flags.config), flags.config);
    config.detector_model = dynamic.model.string();
    config.detector = dynamic.detector;
    config.motion_levels = dynamic.motion_levels;
    config.dynamic_mask = dynamic.mask;
  }
  if (!flags.detector_model.empty()) config.detector_model = flags.detector_model;
  config.Check();
  return config;
}

}  // namespace noctua::app
