#include "noctua/io/openni_camera.h"

#include <OpenNI.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "noctua/io/realtime_source.h"
#include "noctua/util/error.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

namespace noctua::io {
namespace {

// OpenNI2 loads its drivers as plug-ins and never frees what they allocate while starting and
// stopping; LeakSanitizer is told to ignore what is allocated while one of these lives (no-op
// outside sanitizer builds). A suppression ("leak:libOpenNI2.so", as window_sink.cc has for
// libdbus) does not cover it: the drivers have no frame pointers, so with ASan's default fast
// unwinder the allocation stacks are one frame deep, in a driver already unloaded by shutdown()
// ("<unknown module>"); initialize(), a failed open and shutdown() leave 1576 allocations
// (113 KB) reported with or without that suppression.
#if defined(__SANITIZE_ADDRESS__)
using ThirdPartyAllocations = __lsan::ScopedDisabler;
#else
struct ThirdPartyAllocations {};
#endif

std::string DeviceName(const std::string& uri) {
  return uri.empty() ? "OpenNI2 camera" : "OpenNI2 camera " + uri;
}

// OpenNI2's own explanation of the last failure, without its tabs and line breaks.
std::string ExtendedError() {
  std::string text = openni::OpenNI::getExtendedError();
  for (char& c : text) {
    if (c == '\t' || c == '\n') c = ' ';
  }
  const auto first = text.find_first_not_of(' ');
  const auto last = text.find_last_not_of(' ');
  return first == std::string::npos ? "no details" : text.substr(first, last - first + 1);
}

void Require(openni::Status status, const std::string& device, const std::string& what) {
  if (status != openni::STATUS_OK) throw Error(device + ": " + what + " (" + ExtendedError() + ")");
}

// The stream of `sensor` in the asked size and rate with `format`.
void StartStream(openni::Device& device, openni::SensorType sensor, openni::PixelFormat format,
                 const OpenNiOptions& options, openni::VideoStream& stream,
                 const std::string& name) {
  const char* kind = sensor == openni::SENSOR_COLOR ? "colour" : "depth";
  Require(stream.create(device, sensor), name, std::string("no ") + kind + " stream");
  openni::VideoMode mode;
  mode.setResolution(options.width, options.height);
  mode.setFps(options.fps);
  mode.setPixelFormat(format);
  Require(stream.setVideoMode(mode), name,
          std::string("the ") + kind + " stream has no mode " + std::to_string(options.width) +
              "x" + std::to_string(options.height) + " at " + std::to_string(options.fps) + " Hz");
  Require(stream.start(), name, std::string("cannot start the ") + kind + " stream");
}

}  // namespace

void OpenNiOptions::Check() const {
  CheckOption(width > 0 && height > 0, "width and height must be positive");
  CheckOption(fps > 0, "fps must be positive");
  CheckOption(max_frames >= 0, "max_frames must not be negative");
  CheckOption(timeout_s > 0.0, "timeout_s must be positive");
}

struct OpenNiCamera::Impl {
  OpenNiOptions options;
  std::string name;
  openni::Device device;
  openni::VideoStream colour;
  openni::VideoStream depth;
  LatestFrameSlot slot;
  std::atomic<bool> stop{false};
  std::once_flag started;
  std::thread reader;  // started by the first Next()

  ~Impl() {
    [[maybe_unused]] const ThirdPartyAllocations ignored{};
    stop = true;
    if (reader.joinable()) reader.join();
    colour.stop();
    depth.stop();
    colour.destroy();
    depth.destroy();
    device.close();
    openni::OpenNI::shutdown();
  }

  void Read();
  // The frame of a colour and depth pair the camera synchronised.
  SourceFrame Frame(int index, const openni::VideoFrameRef& rgb,
                    const openni::VideoFrameRef& d) const;
};

SourceFrame OpenNiCamera::Impl::Frame(int index, const openni::VideoFrameRef& rgb,
                                      const openni::VideoFrameRef& d) const {
  SourceFrame frame;
  frame.index = index;
  frame.timestamp = static_cast<double>(rgb.getTimestamp()) * 1e-6;
  const cv::Mat rgb_pixels(rgb.getHeight(), rgb.getWidth(), CV_8UC3,
                           const_cast<void*>(rgb.getData()), rgb.getStrideInBytes());
  cv::cvtColor(rgb_pixels, frame.images.bgr, cv::COLOR_RGB2BGR);
  const cv::Mat depth_mm(d.getHeight(), d.getWidth(), CV_16UC1, const_cast<void*>(d.getData()),
                         d.getStrideInBytes());
  depth_mm.convertTo(frame.images.depth_m, CV_32F, 1.0 / 1000.0);
  return frame;
}

void OpenNiCamera::Impl::Read() {
  [[maybe_unused]] const ThirdPartyAllocations ignored{};
  try {
    openni::VideoStream* streams[] = {&colour, &depth};
    openni::VideoFrameRef rgb;
    openni::VideoFrameRef d;
    const int timeout_ms = static_cast<int>(options.timeout_s * 1000.0);
    int index = 0;
    while (!stop && (options.max_frames == 0 || index < options.max_frames)) {
      int ready = -1;
      Require(openni::OpenNI::waitForAnyStream(streams, 2, &ready, timeout_ms), name,
              "no frame for " + std::to_string(options.timeout_s) + " s");
      Require(streams[ready]->readFrame(ready == 0 ? &rgb : &d), name, "cannot read a frame");
      // The device pairs them (depth-colour sync): a pair is the newest of each within half
      // a frame's time.
      if (!rgb.isValid() || !d.isValid()) continue;
      const double dt_s = std::abs(static_cast<double>(rgb.getTimestamp()) -
                                   static_cast<double>(d.getTimestamp())) *
                          1e-6;
      if (dt_s > 0.5 / options.fps) continue;
      slot.Put(Frame(index++, rgb, d));
      rgb.release();
      d.release();
    }
    slot.Close();
  } catch (...) {
    slot.Close(std::current_exception());
  }
}

OpenNiCamera::OpenNiCamera(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OpenNiCamera::~OpenNiCamera() = default;

std::unique_ptr<OpenNiCamera> OpenNiCamera::Open(const OpenNiOptions& options) {
  options.Check();
  [[maybe_unused]] const ThirdPartyAllocations ignored{};
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->name = DeviceName(options.uri);
  Require(openni::OpenNI::initialize(), impl->name, "OpenNI2 does not start");
  if (impl->device.open(options.uri.empty() ? openni::ANY_DEVICE : options.uri.c_str()) !=
      openni::STATUS_OK) {
    throw Error("no " + impl->name + " found: is it plugged in and powered, and may this user " +
                "open it (udev rules)? (" + ExtendedError() + ")");
  }
  StartStream(impl->device, openni::SENSOR_COLOR, openni::PIXEL_FORMAT_RGB888, options,
              impl->colour, impl->name);
  StartStream(impl->device, openni::SENSOR_DEPTH, openni::PIXEL_FORMAT_DEPTH_1_MM, options,
              impl->depth, impl->name);
  Require(impl->device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR),
          impl->name, "cannot register depth to colour");
  Require(impl->device.setDepthColorSyncEnabled(true), impl->name,
          "cannot synchronise depth and colour");
  return std::unique_ptr<OpenNiCamera>(new OpenNiCamera(std::move(impl)));
}

std::string OpenNiCamera::Describe() const { return impl_->name; }
std::optional<SourceFrame> OpenNiCamera::Next() {
  Impl* camera = impl_.get();
  std::call_once(camera->started,
                 [camera] { camera->reader = std::thread([camera] { camera->Read(); }); });
  return camera->slot.Take();
}
std::vector<DroppedFrame> OpenNiCamera::dropped() const { return impl_->slot.dropped(); }

}  // namespace noctua::io
