#pragma once

#include <opencv2/features2d.hpp>
#include <vector>

namespace noctua::features {

// SURF (Bay, Ess, Tuytelaars, Van Gool, "Speeded-Up Robust Features", CVIU 2008), written here
// because Debian's OpenCV is built without the contrib module (xfeatures2d) that holds it.
struct SurfOptions {
  // Points whose Hessian determinant (box-filter responses normalised by box area, on 0-255
  // grey values) is below this are dropped. 100 is OpenCV's default.
  double hessian_threshold = 100.0;
  int num_octaves = 4;        // filter sizes double with every octave
  int num_octave_layers = 3;  // scales per octave between which maxima are sought
  int max_features = 0;       // keep the strongest N (0: all above the threshold)

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// Fast-Hessian detector on the integral image over octaves of growing box filters (9, 15, 21,
// 27 px in the first octave), 3x3x3 non-maximum suppression and quadratic interpolation in
// position and scale; orientation from Haar-wavelet responses in a radius of 6s (sliding window
// of pi/3); 64-d descriptor of 4x4 sub-regions summing dx, |dx|, dy, |dy| over a 20s window
// turned to that orientation, Gaussian-weighted (sigma 3.3s) and unit-normalised.
// KeyPoint semantics follow OpenCV's SURF: size = box filter size (scale s = size * 1.2 / 9),
// angle in degrees, response = determinant, octave = octave index, class_id = Laplacian sign.
class Surf : public cv::Feature2D {
 public:
  static cv::Ptr<Surf> Create(const SurfOptions& options = SurfOptions());
  explicit Surf(const SurfOptions& options);

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints = false) override;
  int descriptorSize() const override { return 64; }
  int descriptorType() const override { return CV_32F; }
  int defaultNorm() const override { return cv::NORM_L2; }
  cv::String getDefaultName() const override { return "noctua.Surf"; }

  const SurfOptions& options() const { return options_; }

 private:
  SurfOptions options_;
};

}  // namespace noctua::features
