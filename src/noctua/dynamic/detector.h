#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "noctua/dynamic/dark_input.h"
#include "noctua/dynamic/detection.h"

namespace noctua::dynamic {

// The model families noctua decodes, recognised from a file's outputs.
enum class ModelKind {
  kYoloV8Head,      // six raw head maps (box distributions + class logits per stride)
  kYoloV8Stock,     // stock Ultralytics export: one [1, 84, N] output
  kYoloV8SegHead,   // nine head maps (+ mask coefficients) and the mask prototypes
  kYoloV8SegStock,  // stock -seg export: [1, 116, N] and the prototypes
  kYoloX,           // YOLOX: one [1, N, 85] output
};
std::string ToString(ModelKind kind);

struct DetectorOptions {
  // Network input, multiples of 32. 320x256 holds a 640x480 frame at half scale without padding:
  // it finds both people of every fr3 walking frame at a third of the 640x480 cost
  // (docs/dynamic.md has the measurements).
  int input_width = 320;
  int input_height = 256;
  float score_threshold = 0.25f;  // Ultralytics' default confidence
  float nms_iou = 0.45f;          // per-class NMS overlap
  int max_detections = 100;
  float mask_threshold = 0.5f;  // instance masks: sigmoid(coefficients . prototypes) > this
  // Dark frames are brightened before the network sees them (on by default; dark_input.h).
  DarkInputOptions dark_input;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Finds COCO objects in an image.
class Detector {
 public:
  virtual ~Detector() = default;
  // image: 8-bit grey, BGR or BGRA, any size. Boxes (and masks) in the image's pixels, best first.
  // Not thread-safe: one Detect at a time per detector.
  virtual std::vector<Detection> Detect(const cv::Mat& image) = 0;
  virtual ModelKind kind() const = 0;
  virtual bool has_masks() const = 0;
  virtual const DetectorOptions& options() const = 0;
};

// Loads an ONNX detector and recognises its kind from its outputs (a forward pass at the
// configured input size); with options.dark_input.enabled, wrapped by MakeDarkAwareDetector. Throws
// noctua::Error naming the file when it is missing, is not an ONNX model OpenCV can read, cannot be
// run by OpenCV, or has outputs of no known family.
std::unique_ptr<Detector> LoadDetector(const std::filesystem::path& model_path,
                                       const DetectorOptions& options = {});

}  // namespace noctua::dynamic
