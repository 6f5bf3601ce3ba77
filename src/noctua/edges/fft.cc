#include "noctua/edges/fft.h"

#include <fftw3.h>

#include <mutex>

#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

// FFTW's planner is not thread-safe; executing plans is.
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

ComplexFft2d::ComplexFft2d(cv::Size size) : size_(size) {
  if (size.width < 1 || size.height < 1) throw Error("FFT: empty size");
  const std::size_t count = static_cast<std::size_t>(size.area());
  std::lock_guard<std::mutex> lock(PlannerMutex());
  fftwf_complex* in = fftwf_alloc_complex(count);
  fftwf_complex* out = fftwf_alloc_complex(count);
  // FFTW_ESTIMATE: planning takes milliseconds, where FFTW_MEASURE takes seconds per size for a
  // gain of about 30% at 320x240.
  forward_ = fftwf_plan_dft_2d(size.height, size.width, in, out, FFTW_FORWARD, FFTW_ESTIMATE);
  inverse_ = fftwf_plan_dft_2d(size.height, size.width, in, out, FFTW_BACKWARD, FFTW_ESTIMATE);
  fftwf_free(in);
  fftwf_free(out);
  if (forward_ == nullptr || inverse_ == nullptr) throw Error("FFT: FFTW could not plan");
}

ComplexFft2d::~ComplexFft2d() {
  std::lock_guard<std::mutex> lock(PlannerMutex());
  fftwf_destroy_plan(static_cast<fftwf_plan>(forward_));
  fftwf_destroy_plan(static_cast<fftwf_plan>(inverse_));
}

void ComplexFft2d::Forward(const cv::Mat& in, cv::Mat& out) const { Execute(forward_, in, out); }

void ComplexFft2d::Inverse(const cv::Mat& in, cv::Mat& out) const { Execute(inverse_, in, out); }

void ComplexFft2d::Execute(void* plan, const cv::Mat& in, cv::Mat& out) const {
  if (in.type() != CV_32FC2 || in.size() != size_ || !in.isContinuous()) {
    throw Error("FFT: input must be a continuous CV_32FC2 matrix of the planned size");
  }
  out.create(size_, CV_32FC2);
  if (out.data == in.data || !out.isContinuous()) throw Error("FFT: output must not alias input");
  // The plans were made on fftwf_alloc'd (SIMD-aligned) arrays; cv::Mat data is 64-byte aligned,
  // so the new-array execute interface applies.
  auto* src = reinterpret_cast<fftwf_complex*>(const_cast<uchar*>(in.data));
  auto* dst = reinterpret_cast<fftwf_complex*>(out.data);
  if (fftwf_alignment_of(reinterpret_cast<float*>(src)) != 0 ||
      fftwf_alignment_of(reinterpret_cast<float*>(dst)) != 0) {
    throw Error("FFT: matrix data is not SIMD-aligned");
  }
  fftwf_execute_dft(static_cast<fftwf_plan>(plan), src, dst);
}

}  // namespace noctua::edges
