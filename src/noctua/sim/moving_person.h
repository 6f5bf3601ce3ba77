#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace noctua::sim {

// A person walking across the view at a fixed distance from the camera, in front of (or
// behind) the real scene according to depth.
struct MovingPersonOptions {
  double height_m = 1.75;          // body height
  double distance_m = 0.9;         // distance along the optical axis (depth of every body pixel)
  double start_x = -0.4;           // horizontal centre at the first frame, in image widths
  double end_x = 1.4;              // ... and at the last frame (walks left to right by default)
  double feet_y = 2.2;             // feet level in image heights (> 1: below the frame, as when
                                   // someone walks close past a desk camera)
  double stride_m = 0.7;           // one step: legs and arms swing once per stride
  std::uint64_t texture_seed = 5;  // clothing pattern (fixed on the body, so it can be matched)
  // With a cut-out: its height on screen in image heights, and where its lower edge is, in image
  // heights (1: on the frame's lower border, as a person cut off by the frame where the cut-out
  // was taken). A cut-out keeps its own proportions; only its depth comes from distance_m.
  double cutout_height = 0.85;
  double cutout_bottom_y = 1.0;

  void Check() const;
};

// A real person's appearance: a colour crop and the mask of the person in it (e.g. a YOLOv8-seg
// instance mask from a frame of a walking sequence). Real people look like people to a detector,
// which a drawn silhouette does not.
struct PersonCutout {
  cv::Mat image;  // 8-bit BGR
  cv::Mat mask;   // CV_8U, image's size, non-zero on the person

  // The crop of `image` to the bounding box of the non-zero pixels of `mask` (same size as
  // `image`). Throws noctua::Error when the mask is empty or the inputs do not fit.
  static PersonCutout FromMask(const cv::Mat& image, const cv::Mat& mask);

  // Throws noctua::Error when the image is not 8-bit BGR, the mask not CV_8U of its size, or the
  // mask is empty.
  void Check() const;
};

// One composited frame.
struct PersonFrame {
  cv::Mat image;  // the input image with the visible part of the person drawn in
  cv::Mat depth;  // 16-bit depth, the person's depth where it is visible
  cv::Mat mask;   // CV_8U, 255 where the person is visible: the ground-truth dynamic mask
};

// Draws a textured silhouette (head, torso, swinging arms and legs) with a high-contrast
// clothing texture, so that feature detectors find points on it, as they do on real people.
class MovingPerson {
 public:
  // focal_px: the camera's focal length in pixels (sizes the body); depth_factor: depth units
  // per metre (5000 for TUM).
  MovingPerson(const MovingPersonOptions& options, double focal_px, double depth_factor);
  // The same walk with a real person's cut-out in place of the drawn silhouette (no limb swing:
  // the cut-out slides across the view).
  MovingPerson(const MovingPersonOptions& options, double focal_px, double depth_factor,
               PersonCutout cutout);

  // progress in [0, 1]: 0 at the first frame of the walk, 1 at the last. The image may be grey,
  // BGR or BGRA 8-bit; depth 16-bit of the same size (0 = no depth: the person covers it).
  PersonFrame Composite(const cv::Mat& image, const cv::Mat& depth16, double progress) const;

 private:
  MovingPersonOptions options_;
  double focal_px_;
  double depth_factor_;
  // Draws the sprite (mask CV_8U, colour BGR), mapped into the image by `to_image`, where the
  // person is nearer than the scene.
  PersonFrame Paint(const cv::Mat& image, const cv::Mat& depth16, const cv::Mat& sprite_mask,
                    const cv::Mat& sprite_colour, const cv::Matx23d& to_image) const;

  bool is_cutout_ = false;
  cv::Mat cutout_colour_;
  cv::Mat cutout_mask_;
  cv::Mat texture_;  // BGR clothing texture in body coordinates (height x height/2 px at 1 px/cm)
};

}  // namespace noctua::sim
