#include "noctua/sim/moving_person.h"

#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "noctua/util/error.h"

namespace noctua::sim {
namespace {

constexpr double kTextureScale = 100.0;  // texture pixels per metre of body

// Clothing: coloured patches, stripes and speckle, at several scales so that corners exist at
// every pyramid level.
cv::Mat MakeTexture(double height_m, std::uint64_t seed) {
  cv::RNG rng(seed);
  const int rows = static_cast<int>(std::ceil(height_m * kTextureScale));
  const int cols = rows / 2;
  cv::Mat texture(rows, cols, CV_8UC3, cv::Scalar(60, 70, 150));
  for (int i = 0; i < 60; ++i) {
    const cv::Point corner(rng.uniform(0, cols), rng.uniform(0, rows));
    const cv::Size size(rng.uniform(4, 25), rng.uniform(4, 25));
    const cv::Scalar colour(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
    if (i % 3 == 0) {
      cv::circle(texture, corner, size.width / 2, colour, cv::FILLED);
    } else {
      cv::rectangle(texture, cv::Rect(corner, size), colour, cv::FILLED);
    }
  }
  for (int y = 0; y < rows; y += 12) {
    cv::line(texture, {0, y}, {cols, y + 6}, cv::Scalar(230, 230, 230), 2);
  }
  cv::Mat speckle(rows, cols, CV_8UC3);
  rng.fill(speckle, cv::RNG::UNIFORM, 0, 60);
  cv::add(texture, speckle, texture);
  return texture;
}

}  // namespace

PersonCutout PersonCutout::FromMask(const cv::Mat& image, const cv::Mat& mask) {
  if (image.type() != CV_8UC3) throw Error("person cut-out: the image must be 8-bit BGR");
  if (mask.type() != CV_8UC1 || mask.size() != image.size()) {
    throw Error("person cut-out: the mask must be 8-bit, one channel, of the image's size");
  }
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) throw Error("person cut-out: the mask is empty");
  PersonCutout cutout{image(box).clone(), mask(box).clone()};
  return cutout;
}

void PersonCutout::Check() const {
  CheckOption(image.type() == CV_8UC3, "person cut-out image must be 8-bit BGR");
  CheckOption(mask.type() == CV_8UC1 && mask.size() == image.size(),
              "person cut-out mask must be 8-bit, one channel, of the image's size");
  CheckOption(cv::countNonZero(mask) > 0, "person cut-out mask is empty");
}

void MovingPersonOptions::Check() const {
  CheckOption(height_m > 0.2 && height_m < 3.0, "person height_m must be in (0.2, 3) m");
  CheckOption(distance_m > 0.1, "person distance_m must be more than 0.1 m");
  CheckOption(std::isfinite(start_x) && std::isfinite(end_x) && std::isfinite(feet_y),
              "person path must be finite");
  CheckOption(stride_m > 0.0, "person stride_m must be positive");
  CheckOption(cutout_height > 0.05 && cutout_height <= 3.0,
              "person cutout_height must be in (0.05, 3] image heights");
  CheckOption(std::isfinite(cutout_bottom_y), "person cutout_bottom_y must be finite");
}

MovingPerson::MovingPerson(const MovingPersonOptions& options, double focal_px, double depth_factor)
    : options_(options), focal_px_(focal_px), depth_factor_(depth_factor) {
  options_.Check();
  CheckOption(focal_px > 0.0, "person compositing needs a positive focal length");
  CheckOption(depth_factor > 0.0, "person compositing needs a positive depth factor");
  CheckOption(options_.distance_m * depth_factor <= 65535.0,
              "person distance does not fit the 16-bit depth format");
  texture_ = MakeTexture(options_.height_m, options_.texture_seed);
}

MovingPerson::MovingPerson(const MovingPersonOptions& options, double focal_px, double depth_factor,
                           PersonCutout cutout)
    : MovingPerson(options, focal_px, depth_factor) {
  cutout.Check();
  is_cutout_ = true;
  cv::compare(cutout.mask, 0, cutout_mask_, cv::CMP_NE);
  // The crop's background would bleed into the person's outline when the colour is interpolated:
  // give every background pixel the colour of its nearest person pixel.
  cv::Mat background = cutout_mask_ == 0;
  cv::Mat distance, labels;
  cv::distanceTransform(background, distance, labels, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<cv::Vec3b> person_colour(1);  // labels count person pixels from 1 in scan order
  for (int y = 0; y < cutout_mask_.rows; ++y) {
    for (int x = 0; x < cutout_mask_.cols; ++x) {
      if (cutout_mask_.at<uchar>(y, x) != 0)
        person_colour.push_back(cutout.image.at<cv::Vec3b>(y, x));
    }
  }
  cutout_colour_ = cutout.image.clone();
  for (int y = 0; y < cutout_mask_.rows; ++y) {
    for (int x = 0; x < cutout_mask_.cols; ++x) {
      const int label = labels.at<int>(y, x);
      if (cutout_mask_.at<uchar>(y, x) == 0 && label > 0 &&
          label < static_cast<int>(person_colour.size())) {
        cutout_colour_.at<cv::Vec3b>(y, x) = person_colour[static_cast<std::size_t>(label)];
      }
    }
  }
}

PersonFrame MovingPerson::Composite(const cv::Mat& image, const cv::Mat& depth16,
                                    double progress) const {
  if (image.empty() || image.depth() != CV_8U) {
    throw Error("person compositing needs an 8-bit image");
  }
  if (depth16.type() != CV_16UC1 || depth16.size() != image.size()) {
    throw Error("person compositing needs a 16-bit depth image of the image's size");
  }
  CheckOption(progress >= 0.0 && progress <= 1.0, "person walk progress must be in [0, 1]");

  if (is_cutout_) {
    // The cut-out slides from start_x to end_x (its centre, in image widths), its lower edge at
    // cutout_bottom_y image heights.
    const double scale = options_.cutout_height * image.rows / cutout_colour_.rows;
    const double centre_x =
        image.cols * (options_.start_x + progress * (options_.end_x - options_.start_x));
    const double left = centre_x - cutout_colour_.cols * scale / 2.0;
    const double top = options_.cutout_bottom_y * image.rows - cutout_colour_.rows * scale;
    return Paint(image, depth16, cutout_mask_, cutout_colour_,
                 cv::Matx23d(scale, 0.0, left, 0.0, scale, top));
  }

  // Body geometry in metres (x right, y down from the top of the head), drawn into a sprite at
  // the texture's resolution and then scaled to the image by perspective.
  const double h = options_.height_m;
  const double px_per_m = focal_px_ / options_.distance_m;
  const double centre_x =
      image.cols * (options_.start_x + progress * (options_.end_x - options_.start_x));
  const double walked_m =
      std::abs(options_.end_x - options_.start_x) * image.cols * progress / px_per_m;
  const double swing = 0.45 * std::sin(2.0 * std::numbers::pi * walked_m / options_.stride_m);

  const int sprite_rows = texture_.rows;
  const int sprite_cols = texture_.cols;
  cv::Mat sprite_mask(sprite_rows, sprite_cols, CV_8UC1, cv::Scalar(0));
  auto at = [&](double x_m, double y_m) {
    return cv::Point(static_cast<int>(std::lround(sprite_cols / 2.0 + x_m * kTextureScale)),
                     static_cast<int>(std::lround(y_m * kTextureScale)));
  };
  auto limb = [&](double x0, double y0, double length, double angle, double width) {
    const cv::Point a = at(x0, y0);
    const cv::Point b = at(x0 + length * std::sin(angle), y0 + length * std::cos(angle));
    cv::line(sprite_mask, a, b, cv::Scalar(255),
             static_cast<int>(std::lround(width * kTextureScale)), cv::LINE_8);
  };
  const cv::Point head = at(0.0, 0.12 * h / 1.75);
  cv::circle(sprite_mask, head, static_cast<int>(0.11 * kTextureScale * h / 1.75), cv::Scalar(255),
             cv::FILLED);
  const double shoulder_y = 0.27 * h;
  const double hip_y = 0.53 * h;
  cv::rectangle(sprite_mask, at(-0.19 * h / 1.75, shoulder_y - 0.03), at(0.19 * h / 1.75, hip_y),
                cv::Scalar(255), cv::FILLED);
  limb(0.0, 0.12 * h, 0.16 * h, 0.0, 0.09);                         // neck
  limb(-0.17 * h / 1.75, hip_y - 0.05, hip_y - 0.02, swing, 0.13);  // legs swing in opposition
  limb(0.17 * h / 1.75 - 0.06, hip_y - 0.05, hip_y - 0.02, -swing, 0.13);
  limb(-0.24 * h / 1.75, shoulder_y, 0.33 * h, -0.6 * swing, 0.08);  // arms
  limb(0.24 * h / 1.75, shoulder_y, 0.33 * h, 0.6 * swing, 0.08);

  // Scale the sprite into the image. The person stands with the feet at feet_y image heights.
  const double scale = px_per_m / kTextureScale;
  const double left = centre_x - sprite_cols * scale / 2.0;
  const double top = options_.feet_y * image.rows - sprite_rows * scale;
  return Paint(image, depth16, sprite_mask, texture_,
               cv::Matx23d(scale, 0.0, left, 0.0, scale, top));
}

PersonFrame MovingPerson::Paint(const cv::Mat& image, const cv::Mat& depth16,
                                const cv::Mat& sprite_mask, const cv::Mat& sprite_colour,
                                const cv::Matx23d& to_image) const {
  cv::Mat body_mask;
  cv::Mat body_colour;
  cv::warpAffine(sprite_mask, body_mask, to_image, image.size(), cv::INTER_NEAREST,
                 cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::warpAffine(sprite_colour, body_colour, to_image, image.size(), cv::INTER_LINEAR,
                 cv::BORDER_REPLICATE);

  // The person is visible where it is nearer than the scene or where the scene has no depth.
  const auto person_depth =
      static_cast<std::uint16_t>(std::lround(options_.distance_m * depth_factor_));
  PersonFrame frame;
  frame.image = image.clone();
  frame.depth = depth16.clone();
  frame.mask = cv::Mat(image.size(), CV_8UC1, cv::Scalar(0));
  cv::Mat colour_for_image;
  if (image.channels() == 1) {
    cv::cvtColor(body_colour, colour_for_image, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(body_colour, colour_for_image, cv::COLOR_BGR2BGRA);
  } else {
    colour_for_image = body_colour;
  }
  const std::size_t pixel_bytes = image.elemSize();
  for (int y = 0; y < image.rows; ++y) {
    const uchar* body = body_mask.ptr<uchar>(y);
    const std::uint16_t* scene = depth16.ptr<std::uint16_t>(y);
    std::uint16_t* depth_out = frame.depth.ptr<std::uint16_t>(y);
    uchar* mask_out = frame.mask.ptr<uchar>(y);
    uchar* image_out = frame.image.ptr<uchar>(y);
    const uchar* colour = colour_for_image.ptr<uchar>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (body[x] == 0 || (scene[x] != 0 && scene[x] <= person_depth)) continue;
      depth_out[x] = person_depth;
      mask_out[x] = 255;
      std::copy_n(colour + x * pixel_bytes, pixel_bytes, image_out + x * pixel_bytes);
    }
  }
  return frame;
}

}  // namespace noctua::sim
