#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace noctua::viz {

// Panels shown in an OpenCV (highgui) window as they come. Keys: space pauses and resumes, q or
// Esc asks the run to stop.
class WindowSink {
 public:
  // Opens the window. Throws noctua::Error when no display can be opened (no DISPLAY or
  // WAYLAND_DISPLAY, or the X server refuses), instead of letting the GUI toolkit abort.
  explicit WindowSink(std::string title);
  ~WindowSink();
  WindowSink(const WindowSink&) = delete;
  WindowSink& operator=(const WindowSink&) = delete;

  // Shows the panel and handles the keys (waits while paused). Returns false once the user
  // asked to stop.
  bool Show(const cv::Mat& panel);
  bool stop_requested() const { return stop_requested_; }

  // Writes what the screen shows now (the X server's root window, so the window as drawn, not
  // the panel given to it) as an image file. Throws noctua::Error when it cannot.
  void SaveScreenshot(const std::filesystem::path& path);

 private:
  std::string title_;
  bool stop_requested_ = false;
};

// The X server's root window as BGR, read with Xlib; throws noctua::Error without a display.
cv::Mat GrabScreen();

}  // namespace noctua::viz
