#include "noctua/viz/window_sink.h"

#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <cstdlib>
#include <memory>
#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>

#include "noctua/util/error.h"

#if defined(__SANITIZE_ADDRESS__)
// OpenCV's window (Qt) connects to D-Bus on threads of its own and leaves libdbus's buffers to
// the process's end: not ours, and not reachable to free. LeakSanitizer is told so; any other
// leak is still reported.
extern "C" const char* __lsan_default_suppressions() { return "leak:libdbus-1.so\n"; }
#endif

namespace noctua::viz {
namespace {

constexpr int kSpace = 32;
constexpr int kEscape = 27;

bool IsStopKey(int key) { return key == 'q' || key == 'Q' || key == kEscape; }

struct DisplayCloser {
  void operator()(Display* display) const { XCloseDisplay(display); }
};
using DisplayPtr = std::unique_ptr<Display, DisplayCloser>;

// The display the window would open on; throws when there is none, before the toolkit tries.
DisplayPtr OpenDisplay() {
  const char* name = std::getenv("DISPLAY");
  if (name == nullptr || *name == '\0') {
    throw Error("viewer: no display (DISPLAY is not set); write the panels with --video instead");
  }
  DisplayPtr display(XOpenDisplay(nullptr));
  if (display == nullptr) {
    throw Error(std::string("viewer: cannot open display '") + name +
                "'; write the panels with --video instead");
  }
  return display;
}

}  // namespace

WindowSink::WindowSink(std::string title) : title_(std::move(title)) {
  OpenDisplay();
  try {
    // Without the toolbar of the Qt backend: the window shows the panel as drawn.
    cv::namedWindow(title_, cv::WINDOW_AUTOSIZE | cv::WINDOW_GUI_NORMAL);
  } catch (const cv::Exception& error) {
    throw Error("viewer: cannot open a window: " + std::string(error.what()));
  }
}

WindowSink::~WindowSink() {
  try {
    cv::destroyWindow(title_);
    cv::waitKey(1);
  } catch (const cv::Exception&) {
    // Already gone with its display: nothing to close.
  }
}

bool WindowSink::Show(const cv::Mat& panel) {
  if (stop_requested_) return false;
  cv::imshow(title_, panel);
  int key = cv::waitKey(1);
  if (key == kSpace) {
    // Paused until space again; q or Esc still stop.
    do {
      key = cv::waitKey(50);
    } while (key != kSpace && !IsStopKey(key) &&
             cv::getWindowProperty(title_, cv::WND_PROP_VISIBLE) > 0);
  }
  // A window closed by its close button counts as a request to stop.
  stop_requested_ = IsStopKey(key) || cv::getWindowProperty(title_, cv::WND_PROP_VISIBLE) <= 0;
  return !stop_requested_;
}

void WindowSink::SaveScreenshot(const std::filesystem::path& path) {
  // Let the toolkit handle the pending expose events, so the window is drawn when grabbed.
  for (int i = 0; i < 10; ++i) cv::waitKey(20);
  const cv::Mat screen = GrabScreen();
  if (!cv::imwrite(path.string(), screen)) {
    throw Error("viewer: cannot write the screenshot " + path.string());
  }
}

cv::Mat GrabScreen() {
  const DisplayPtr display = OpenDisplay();
  const Window root = DefaultRootWindow(display.get());
  XWindowAttributes attributes;
  XGetWindowAttributes(display.get(), root, &attributes);
  XImage* image = XGetImage(display.get(), root, 0, 0, static_cast<unsigned>(attributes.width),
                            static_cast<unsigned>(attributes.height), AllPlanes, ZPixmap);
  if (image == nullptr) throw Error("viewer: cannot read the screen");
  cv::Mat bgr(attributes.height, attributes.width, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const unsigned long pixel = XGetPixel(image, x, y);
      bgr.at<cv::Vec3b>(y, x) = {static_cast<uchar>(pixel & image->blue_mask),
                                 static_cast<uchar>((pixel & image->green_mask) >> 8),
                                 static_cast<uchar>((pixel & image->red_mask) >> 16)};
    }
  }
  XDestroyImage(image);
  return bgr;
}

}  // namespace noctua::viz
