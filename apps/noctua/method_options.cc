#include "method_options.h"

#include "noctua/pipeline/method_config.h"

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
  return pipeline::LoadMethodConfig(flags.config, flags.detector_model);
}

}  // namespace noctua::app
