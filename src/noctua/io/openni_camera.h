#pragma once

#include <memory>
#include <string>

#include "noctua/io/frame_source.h"

namespace noctua::io {

// A live RGB-D camera through OpenNI2 (Kinect, Xtion, Carmine; an .oni recording's path works
// too): colour and depth at the camera's rate, depth registered to colour and synchronised.
struct OpenNiOptions {
  std::string uri;  // "": the first camera found
  int width = 640;  // the video mode asked for, colour and depth
  int height = 480;
  int fps = 30;
  int max_frames = 0;      // stop after this many frames from the camera; 0: until closed
  double timeout_s = 2.0;  // the camera is taken as gone after this long without a frame

  void Check() const;
};

// The frames a camera delivers, read on a thread of their own from the first Next() on (the
// camera streams from Open(), but frames before the reader is ready are not its drops); a reader
// still busy with an earlier frame gets only the newest (LatestFrameSlot), the others are
// dropped().
class OpenNiCamera : public FrameSource {
 public:
  // Throws noctua::Error when OpenNI2 finds no camera (at `uri`), or the camera has no colour
  // and depth stream in the asked mode, or cannot register depth to colour.
  static std::unique_ptr<OpenNiCamera> Open(const OpenNiOptions& options = {});
  ~OpenNiCamera() override;

  std::string Describe() const override;
  bool real_time() const override { return true; }
  std::optional<std::size_t> size() const override { return std::nullopt; }
  std::optional<SourceFrame> Next() override;
  std::vector<DroppedFrame> dropped() const override;

 private:
  struct Impl;
  explicit OpenNiCamera(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace noctua::io
