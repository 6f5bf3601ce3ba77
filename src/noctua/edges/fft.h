#pragma once

#include <opencv2/core.hpp>

namespace noctua::edges {

// Complex 2-D FFTs of one size through FFTW3 (single precision), which measured about five times
// faster than cv::dft here (docs/edges.md). Plans are made once, at construction; executing them
// is thread-safe.
class ComplexFft2d {
 public:
  explicit ComplexFft2d(cv::Size size);
  ~ComplexFft2d();
  ComplexFft2d(const ComplexFft2d&) = delete;
  ComplexFft2d& operator=(const ComplexFft2d&) = delete;

  // Unnormalised transforms of a continuous CV_32FC2 matrix of the planned size into `out`
  // (allocated as needed; must not alias `in`). Throws noctua::Error for other input.
  void Forward(const cv::Mat& in, cv::Mat& out) const;
  void Inverse(const cv::Mat& in, cv::Mat& out) const;

  cv::Size size() const { return size_; }

 private:
  void Execute(void* plan, const cv::Mat& in, cv::Mat& out) const;

  cv::Size size_;
  void* forward_ = nullptr;  // fftwf_plan, kept opaque so that users need not include fftw3.h
  void* inverse_ = nullptr;
};

}  // namespace noctua::edges
