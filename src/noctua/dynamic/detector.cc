#include "noctua/dynamic/detector.h"

#include <array>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "noctua/dynamic/coco.h"
#include "noctua/dynamic/decode.h"
#include "noctua/dynamic/letterbox.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

constexpr std::array<int, 3> kStrides = {8, 16, 32};
constexpr int kMaskCoefficients = 32;

std::string Shape(const cv::Mat& blob) {
  std::ostringstream out;
  out << "[";
  for (int d = 0; d < blob.dims; ++d) out << (d ? ", " : "") << blob.size[d];
  out << "]";
  return out.str();
}

cv::Mat ToBgr(const cv::Mat& image) {
  if (image.empty()) throw Error("detector: empty image");
  if (image.depth() != CV_8U) throw Error("detector: expected an 8-bit image");
  cv::Mat bgr;
  switch (image.channels()) {
    case 1:
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    case 3:
      return image;
    case 4:
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
      return bgr;
    default:
      throw Error("detector: expected 1, 3 or 4 channels, got " + std::to_string(image.channels()));
  }
}

int Anchors(cv::Size input) {
  int n = 0;
  for (int s : kStrides) n += (input.width / s) * (input.height / s);
  return n;
}

// Where each tensor of a recognised model sits in the forward() outputs.
struct Layout {
  ModelKind kind = ModelKind::kYoloV8Head;
  std::array<int, 3> box{-1, -1, -1}, cls{-1, -1, -1}, coeff{-1, -1, -1};
  int proto = -1;
  int single = -1;
};

// Recognises the family from output shapes alone: output names differ between exporters, while
// the shapes follow from the architecture and the input size.
std::optional<Layout> Recognise(const std::vector<cv::Mat>& outs, cv::Size input) {
  Layout layout;
  int four_d = 0, three_d = 0, other = 0;
  for (int i = 0; i < static_cast<int>(outs.size()); ++i) {
    const cv::Mat& m = outs[static_cast<size_t>(i)];
    if (m.dims == 4 && m.size[0] == 1) {
      ++four_d;
      const int c = m.size[1], h = m.size[2], w = m.size[3];
      if (h <= 0 || w <= 0 || input.height % h != 0 || input.width / w != input.height / h ||
          input.width % w != 0) {
        return std::nullopt;
      }
      const int s = input.height / h;
      if (s == 4 && c == kMaskCoefficients && layout.proto < 0) {
        layout.proto = i;
        continue;
      }
      const auto level = std::find(kStrides.begin(), kStrides.end(), s);
      if (level == kStrides.end()) return std::nullopt;
      const auto l = static_cast<size_t>(level - kStrides.begin());
      int* slot = c == 64                  ? &layout.box[l]
                  : c == kNumCocoClasses   ? &layout.cls[l]
                  : c == kMaskCoefficients ? &layout.coeff[l]
                                           : nullptr;
      if (slot == nullptr || *slot >= 0) return std::nullopt;
      *slot = i;
    } else if (m.dims == 3 && m.size[0] == 1) {
      ++three_d;
      layout.single = i;
    } else {
      ++other;
    }
  }
  const auto complete = [](const std::array<int, 3>& a) {
    return a[0] >= 0 && a[1] >= 0 && a[2] >= 0;
  };
  const auto none = [](const std::array<int, 3>& a) { return a[0] < 0 && a[1] < 0 && a[2] < 0; };
  if (other > 0) return std::nullopt;
  const int n = Anchors(input);
  if (three_d == 0 && complete(layout.box) && complete(layout.cls)) {
    if (four_d == 6 && layout.proto < 0) {
      layout.kind = ModelKind::kYoloV8Head;
      return layout;
    }
    if (four_d == 10 && complete(layout.coeff) && layout.proto >= 0) {
      layout.kind = ModelKind::kYoloV8SegHead;
      return layout;
    }
    return std::nullopt;
  }
  if (three_d != 1 || !none(layout.box) || !none(layout.cls) || !none(layout.coeff)) {
    return std::nullopt;
  }
  const cv::Mat& single = outs[static_cast<size_t>(layout.single)];
  const int a = single.size[1], b = single.size[2];
  if (four_d == 0 && a == 4 + kNumCocoClasses && b == n) {
    layout.kind = ModelKind::kYoloV8Stock;
    return layout;
  }
  if (four_d == 1 && layout.proto >= 0 && a == 4 + kNumCocoClasses + kMaskCoefficients && b == n) {
    layout.kind = ModelKind::kYoloV8SegStock;
    return layout;
  }
  if (four_d == 0 && a == n && b == 5 + kNumCocoClasses) {
    layout.kind = ModelKind::kYoloX;
    return layout;
  }
  return std::nullopt;
}

class OnnxDetector : public Detector {
 public:
  OnnxDetector(cv::dnn::Net net, std::vector<std::string> names, Layout layout,
               const DetectorOptions& options)
      : net_(std::move(net)), names_(std::move(names)), layout_(layout), options_(options) {}

  std::vector<Detection> Detect(const cv::Mat& image) override {
    const cv::Mat bgr = ToBgr(image);
    const Letterbox letterbox(bgr.size(), input_size(), centered());
    const cv::Mat input = letterbox.Apply(bgr);
    net_.setInput(cv::dnn::blobFromImage(input, pixel_scale(), cv::Size(), cv::Scalar(), swap_rb(),
                                         false, CV_32F));
    std::vector<cv::Mat> outs;
    net_.forward(outs, names_);
    std::vector<Candidate> kept =
        PerClassNms(Decode(outs), options_.nms_iou, options_.max_detections);
    std::vector<Detection> detections;
    for (const Candidate& candidate : kept) {
      Detection detection;
      detection.box = letterbox.ToOriginal(candidate.box);
      if (detection.box.area() <= 0.0f) continue;
      detection.class_id = candidate.class_id;
      detection.score = candidate.score;
      detection.mask = Mask(outs, candidate, letterbox, detection.box);
      detections.push_back(std::move(detection));
    }
    return detections;
  }

  ModelKind kind() const override { return layout_.kind; }
  bool has_masks() const override { return layout_.proto >= 0; }
  const DetectorOptions& options() const override { return options_; }

 protected:
  cv::Size input_size() const { return {options_.input_width, options_.input_height}; }
  const Layout& layout() const { return layout_; }
  virtual bool centered() const = 0;
  virtual double pixel_scale() const = 0;
  virtual bool swap_rb() const = 0;
  virtual std::vector<Candidate> Decode(const std::vector<cv::Mat>& outs) const = 0;
  virtual cv::Mat Mask(const std::vector<cv::Mat>&, const Candidate&, const Letterbox&,
                       const cv::Rect2f&) const {
    return {};
  }

 private:
  cv::dnn::Net net_;
  std::vector<std::string> names_;
  Layout layout_;
  DetectorOptions options_;
};

// YOLOv8 detection, head or stock export: RGB in [0, 1], centred letterbox.
class YoloV8Detector : public OnnxDetector {
 public:
  using OnnxDetector::OnnxDetector;

 protected:
  bool centered() const override { return true; }
  double pixel_scale() const override { return 1.0 / 255.0; }
  bool swap_rb() const override { return true; }
  std::vector<Candidate> Decode(const std::vector<cv::Mat>& outs) const override {
    if (layout().single >= 0) {
      return DecodeYoloV8Stock(outs[static_cast<size_t>(layout().single)], kNumCocoClasses,
                               options().score_threshold);
    }
    std::vector<YoloV8HeadLevel> levels;
    for (size_t l = 0; l < kStrides.size(); ++l) {
      levels.push_back({outs[static_cast<size_t>(layout().box[l])],
                        outs[static_cast<size_t>(layout().cls[l])], kStrides[l]});
    }
    return DecodeYoloV8Head(levels, options().score_threshold);
  }
};

// YOLOv8-seg: the detection decoding plus instance masks from coefficients x prototypes.
class YoloV8SegDetector : public YoloV8Detector {
 public:
  using YoloV8Detector::YoloV8Detector;

 protected:
  cv::Mat Mask(const std::vector<cv::Mat>& outs, const Candidate& candidate,
               const Letterbox& letterbox, const cv::Rect2f& box) const override {
    std::array<float, kMaskCoefficients> coefficients{};
    if (layout().single >= 0) {
      const cv::Mat& single = outs[static_cast<size_t>(layout().single)];
      const int n = single.size[2];
      const float* data = single.ptr<float>();
      for (int k = 0; k < kMaskCoefficients; ++k) {
        coefficients[static_cast<size_t>(k)] =
            data[static_cast<size_t>(4 + kNumCocoClasses + k) * n + candidate.anchor];
      }
    } else {
      int cell = candidate.anchor;
      for (size_t l = 0; l < kStrides.size(); ++l) {
        const cv::Mat& map = outs[static_cast<size_t>(layout().coeff[l])];
        const int plane = map.size[2] * map.size[3];
        if (cell >= plane) {
          cell -= plane;
          continue;
        }
        const float* data = map.ptr<float>();
        for (int k = 0; k < kMaskCoefficients; ++k) {
          coefficients[static_cast<size_t>(k)] = data[static_cast<size_t>(k) * plane + cell];
        }
        break;
      }
    }
    const cv::Mat in_input =
        YoloV8InstanceMask(outs[static_cast<size_t>(layout().proto)], coefficients.data(),
                           candidate.box, input_size(), options().mask_threshold);
    cv::Mat full;
    cv::resize(in_input(letterbox.ContentRect()), full, letterbox.original(), 0, 0,
               cv::INTER_LINEAR);
    cv::Mat mask = cv::Mat::zeros(full.size(), CV_8U);
    const cv::Rect inside =
        cv::Rect(cvFloor(box.x), cvFloor(box.y), cvCeil(box.width) + 1, cvCeil(box.height) + 1) &
        cv::Rect(cv::Point(), full.size());
    mask(inside).setTo(255, full(inside) > 127);
    return mask;
  }
};

// YOLOX: BGR in 0..255, top-left letterbox.
class YoloXDetector : public OnnxDetector {
 public:
  using OnnxDetector::OnnxDetector;

 protected:
  bool centered() const override { return false; }
  double pixel_scale() const override { return 1.0; }
  bool swap_rb() const override { return false; }
  std::vector<Candidate> Decode(const std::vector<cv::Mat>& outs) const override {
    return DecodeYoloX(outs[static_cast<size_t>(layout().single)], input_size(),
                       options().score_threshold);
  }
};

}  // namespace

std::string ToString(ModelKind kind) {
  switch (kind) {
    case ModelKind::kYoloV8Head:
      return "yolov8-head";
    case ModelKind::kYoloV8Stock:
      return "yolov8-stock";
    case ModelKind::kYoloV8SegHead:
      return "yolov8-seg-head";
    case ModelKind::kYoloV8SegStock:
      return "yolov8-seg-stock";
    case ModelKind::kYoloX:
      return "yolox";
  }
  return "unknown";
}

void DetectorOptions::Check() const {
  CheckOption(input_width >= 32 && input_width % 32 == 0,
              "detector input_width must be a positive multiple of 32");
  CheckOption(input_height >= 32 && input_height % 32 == 0,
              "detector input_height must be a positive multiple of 32");
  CheckOption(score_threshold > 0.0f && score_threshold < 1.0f,
              "detector score_threshold must be in (0, 1)");
  CheckOption(nms_iou > 0.0f && nms_iou <= 1.0f, "detector nms_iou must be in (0, 1]");
  CheckOption(max_detections >= 1, "detector max_detections must be at least 1");
  CheckOption(mask_threshold > 0.0f && mask_threshold < 1.0f,
              "detector mask_threshold must be in (0, 1)");
  dark_input.Check();
}

namespace {

std::unique_ptr<Detector> LoadNetwork(const std::filesystem::path& model_path,
                                      const DetectorOptions& options) {
  std::error_code error;
  if (!std::filesystem::exists(model_path, error)) {
    ThrowFileError(model_path, "detector model not found");
  }
  if (!std::filesystem::is_regular_file(model_path, error)) {
    ThrowFileError(model_path, "detector model is not a file");
  }
  cv::dnn::Net net;
  try {
    net = cv::dnn::readNetFromONNX(model_path.string());
  } catch (const cv::Exception& e) {
    ThrowFileError(model_path, "not an ONNX model OpenCV can read (" + e.err + ")");
  }
  if (net.empty()) ThrowFileError(model_path, "not an ONNX model OpenCV can read (empty network)");
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  const cv::Size input(options.input_width, options.input_height);
  std::vector<std::string> names = net.getUnconnectedOutLayersNames();
  std::vector<cv::Mat> outs;
  try {
    // One pass on a grey frame reveals the output shapes, hence the family, and warms up the
    // network so that the first real frame is not slower than the others.
    net.setInput(cv::dnn::blobFromImage(cv::Mat(input, CV_8UC3, cv::Scalar::all(114)), 1.0 / 255,
                                        cv::Size(), cv::Scalar(), true, false, CV_32F));
    net.forward(outs, names);
  } catch (const cv::Exception& e) {
    ThrowFileError(model_path,
                   "OpenCV " CV_VERSION " cannot run this model at " + std::to_string(input.width) +
                       "x" + std::to_string(input.height) + " (" + e.err +
                       "); stock Ultralytics YOLOv8 exports need OpenCV 4.7 or later, use a head "
                       "export (docs/dynamic.md)");
  }
  const std::optional<Layout> layout = Recognise(outs, input);
  if (!layout) {
    std::string shapes;
    for (const cv::Mat& m : outs) shapes += (shapes.empty() ? "" : ", ") + Shape(m);
    ThrowFileError(model_path,
                   "unexpected outputs " + shapes + " at input " + std::to_string(input.width) +
                       "x" + std::to_string(input.height) +
                       "; expected a COCO YOLOv8 head export (box [1,64,H/s,W/s] and class "
                       "[1,80,H/s,W/s] maps for s = 8, 16, 32, plus coefficients and prototypes "
                       "for -seg), a stock YOLOv8 export [1,84,N] or [1,116,N] + prototypes, or "
                       "YOLOX [1,N,85]");
  }
  switch (layout->kind) {
    case ModelKind::kYoloV8Head:
    case ModelKind::kYoloV8Stock:
      return std::make_unique<YoloV8Detector>(std::move(net), std::move(names), *layout, options);
    case ModelKind::kYoloV8SegHead:
    case ModelKind::kYoloV8SegStock:
      return std::make_unique<YoloV8SegDetector>(std::move(net), std::move(names), *layout,
                                                 options);
    case ModelKind::kYoloX:
      return std::make_unique<YoloXDetector>(std::move(net), std::move(names), *layout, options);
  }
  ThrowFileError(model_path, "unsupported model family");
}

}  // namespace

std::unique_ptr<Detector> LoadDetector(const std::filesystem::path& model_path,
                                       const DetectorOptions& options) {
  options.Check();
  std::unique_ptr<Detector> detector = LoadNetwork(model_path, options);
  if (!options.dark_input.enabled) return detector;
  return MakeDarkAwareDetector(std::move(detector), options.dark_input);
}

}  // namespace noctua::dynamic
