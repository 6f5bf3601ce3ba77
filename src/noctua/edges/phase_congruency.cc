#include "noctua/edges/phase_congruency.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <numbers>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "noctua/edges/fft.h"
#include "noctua/util/error.h"

namespace noctua::edges {
namespace {

constexpr double kPi = std::numbers::pi;

void CheckFilterBank(int nscale, double min_wavelength, double mult, double sigma_on_f,
                     double lowpass_cutoff, int lowpass_order, double k, double cut_off, double g,
                     double epsilon) {
  CheckOption(nscale >= 2 && nscale <= 8,
              "nscale must be in [2, 8] (the frequency spread "
              "weighting needs at least two scales)");
  CheckOption(min_wavelength > 1.0, "min_wavelength must be > 1 pixel");
  CheckOption(mult > 1.0, "mult must be > 1");
  CheckOption(sigma_on_f > 0.0 && sigma_on_f < 1.0, "sigma_on_f must be in (0, 1)");
  CheckOption(lowpass_cutoff > 0.0 && lowpass_cutoff <= 0.5, "lowpass_cutoff must be in (0, 0.5]");
  CheckOption(lowpass_order >= 1, "lowpass_order must be >= 1");
  CheckOption(k >= 0.0, "k must be >= 0");
  CheckOption(cut_off >= 0.0 && cut_off <= 1.0, "cut_off must be in [0, 1]");
  CheckOption(g > 0.0, "g must be > 0");
  CheckOption(epsilon > 0.0, "epsilon must be > 0");
}

// Normalised frequency (cycles per pixel) of DFT index i of n samples, with the ranges of
// Kovesi's meshgrid + ifftshift (odd sizes are normalised by n - 1, as in his code).
double Frequency(int i, int n) {
  if (n % 2 == 1) {
    const int half = (n - 1) / 2;
    return static_cast<double>(i <= half ? i : i - n) / (n - 1);
  }
  return static_cast<double>(i < n / 2 ? i : i - n) / n;
}

// Throws unless the input is what phase congruency needs.
void CheckGray(const cv::Mat& gray, int min_size) {
  if (gray.empty()) throw Error("phase congruency: the image is empty");
  if (gray.channels() != 1) {
    throw Error("phase congruency: the image must be single-channel grey, got " +
                std::to_string(gray.channels()) + " channels");
  }
  if (gray.rows < min_size || gray.cols < min_size) {
    throw Error("phase congruency: the image is " + std::to_string(gray.cols) + "x" +
                std::to_string(gray.rows) + ", smaller than the minimum " +
                std::to_string(min_size) + "x" + std::to_string(min_size));
  }
}

cv::Mat ToFloatGray(const cv::Mat& gray, int min_size) {
  CheckGray(gray, min_size);
  cv::Mat result;
  gray.convertTo(result, CV_32F);
  return result;
}

void Zeros(cv::Mat& mat, int rows, int cols) {
  mat.create(rows, cols, CV_32F);
  mat.setTo(0.0f);
}

// Median of a float image (the noise estimate's statistic): the value of rank n / 2, as
// std::nth_element gives it. Amplitudes are non-negative, and the bit patterns of non-negative
// floats order like their values, so a histogram of the upper 16 bits finds the bin that holds
// that rank in one pass, and only that bin's few values are then ordered: about 5x faster than
// nth_element over the whole image, with the same result.
double Median(const cv::Mat& values) {
  const std::size_t rank = values.total() / 2;
  std::vector<std::uint32_t> histogram(std::size_t{1} << 16, 0);
  bool negative_or_nan = false;
  for (int r = 0; r < values.rows; ++r) {
    const float* row = values.ptr<float>(r);
    for (int c = 0; c < values.cols; ++c) {
      negative_or_nan |= !(row[c] >= 0.0f);
      std::uint32_t bits = 0;
      std::memcpy(&bits, &row[c], sizeof bits);
      ++histogram[bits >> 16];
    }
  }
  std::vector<float> candidates;
  std::size_t target = rank;
  std::uint32_t bin = 0;
  if (!negative_or_nan) {
    std::size_t below = 0;
    while (below + histogram[bin] <= rank) below += histogram[bin++];
    target = rank - below;
    candidates.reserve(histogram[bin]);
  } else {
    candidates.reserve(values.total());
  }
  for (int r = 0; r < values.rows; ++r) {
    const float* row = values.ptr<float>(r);
    for (int c = 0; c < values.cols; ++c) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &row[c], sizeof bits);
      if (negative_or_nan || bits >> 16 == bin) candidates.push_back(row[c]);
    }
  }
  const auto middle = candidates.begin() + static_cast<std::ptrdiff_t>(target);
  std::nth_element(candidates.begin(), middle, candidates.end());
  return *middle;
}

// Radial log-Gabor filters (times the low-pass), one per scale, as CV_32F spectra laid out like
// cv::dft's output. Also returns the frequency grid for the angular and Riesz filters.
struct FrequencyGrid {
  cv::Mat u;       // horizontal frequency
  cv::Mat v;       // vertical frequency (positive downwards, as rows grow)
  cv::Mat radius;  // with radius(0, 0) = 1 to avoid log(0), as Kovesi
};

FrequencyGrid MakeGrid(int rows, int cols) {
  FrequencyGrid grid{cv::Mat(rows, cols, CV_32F), cv::Mat(rows, cols, CV_32F),
                     cv::Mat(rows, cols, CV_32F)};
  for (int r = 0; r < rows; ++r) {
    const double v = Frequency(r, rows);
    for (int c = 0; c < cols; ++c) {
      const double u = Frequency(c, cols);
      grid.u.at<float>(r, c) = static_cast<float>(u);
      grid.v.at<float>(r, c) = static_cast<float>(v);
      grid.radius.at<float>(r, c) = static_cast<float>(std::sqrt(u * u + v * v));
    }
  }
  grid.radius.at<float>(0, 0) = 1.0f;
  return grid;
}

std::vector<cv::Mat> MakeLogGabors(const FrequencyGrid& grid, int nscale, double min_wavelength,
                                   double mult, double sigma_on_f, double lowpass_cutoff,
                                   int lowpass_order) {
  const double log_sigma2 = 2.0 * std::log(sigma_on_f) * std::log(sigma_on_f);
  std::vector<cv::Mat> filters;
  for (int s = 0; s < nscale; ++s) {
    const double fo = 1.0 / (min_wavelength * std::pow(mult, s));
    cv::Mat filter(grid.radius.size(), CV_32F);
    for (int r = 0; r < filter.rows; ++r) {
      const float* radius = grid.radius.ptr<float>(r);
      float* out = filter.ptr<float>(r);
      for (int c = 0; c < filter.cols; ++c) {
        const double lr = std::log(radius[c] / fo);
        const double lowpass =
            1.0 / (1.0 + std::pow(radius[c] / lowpass_cutoff, 2.0 * lowpass_order));
        out[c] = static_cast<float>(std::exp(-lr * lr / log_sigma2) * lowpass);
      }
    }
    filter.at<float>(0, 0) = 0.0f;  // no DC response
    filters.push_back(filter);
  }
  return filters;
}

// Noise threshold from the smallest scale's median amplitude (Rayleigh statistics).
double NoiseThreshold(double median_amplitude, int nscale, double mult, double k) {
  const double tau = median_amplitude / std::sqrt(std::log(4.0));
  const double total_tau = tau * (1.0 - std::pow(1.0 / mult, nscale)) / (1.0 - 1.0 / mult);
  const double noise_mean = total_tau * std::sqrt(kPi / 2.0);
  const double noise_sigma = total_tau * std::sqrt((4.0 - kPi) / 2.0);
  return noise_mean + k * noise_sigma;
}

// The feature normal from the angle of the summed monogenic vector (h1, -h2) in degrees, as
// radians in [0, pi). OpenCV's fast arc tangent (about 0.3 degree error) is ample for NMS, which
// works in whole degrees.
float NormalFromDegrees(float degrees) {
  constexpr auto kPiF = static_cast<float>(kPi);
  float a = degrees * (kPiF / 180.0f);
  if (a >= kPiF) a -= kPiF;
  if (a >= kPiF) a = 0.0f;
  return a;
}

// out = spectrum * real_filter, element-wise (complex times real).
void MultiplyByReal(const cv::Mat& spectrum, const cv::Mat& filter, cv::Mat& out) {
  out.create(spectrum.size(), CV_32FC2);
  for (int r = 0; r < spectrum.rows; ++r) {
    const float* in = spectrum.ptr<float>(r);
    const float* f = filter.ptr<float>(r);
    float* o = out.ptr<float>(r);
    for (int c = 0; c < spectrum.cols; ++c) {
      o[2 * c] = in[2 * c] * f[c];
      o[2 * c + 1] = in[2 * c + 1] * f[c];
    }
  }
}

}  // namespace

void PhaseCongruencyOptions::Check() const {
  CheckFilterBank(nscale, min_wavelength, mult, sigma_on_f, lowpass_cutoff, lowpass_order, k,
                  cut_off, g, epsilon);
  CheckOption(norient >= 1 && norient <= 16, "norient must be in [1, 16]");
}

void FastPhaseCongruencyOptions::Check() const {
  CheckFilterBank(nscale, min_wavelength, mult, sigma_on_f, lowpass_cutoff, lowpass_order, k,
                  cut_off, g, epsilon);
  CheckOption(deviation_gain >= 0.0, "deviation_gain must be >= 0");
  CheckOption(downscale == 1 || downscale == 2 || downscale == 4, "downscale must be 1, 2 or 4");
  CheckOption(min_wavelength / downscale > 1.0,
              "min_wavelength / downscale must be > 1 pixel of the reduced image");
}

PhaseCongruency ComputePhaseCongruency(const cv::Mat& gray, const PhaseCongruencyOptions& o) {
  o.Check();
  const cv::Mat image = ToFloatGray(gray, kMinPhaseCongruencySize);
  const int rows = image.rows;
  const int cols = image.cols;
  cv::Mat image_fft;
  cv::dft(image, image_fft, cv::DFT_COMPLEX_OUTPUT);

  const FrequencyGrid grid = MakeGrid(rows, cols);
  const std::vector<cv::Mat> log_gabor = MakeLogGabors(
      grid, o.nscale, o.min_wavelength, o.mult, o.sigma_on_f, o.lowpass_cutoff, o.lowpass_order);
  cv::Mat theta(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      // Negated v: angles are anticlockwise with y pointing up, as Kovesi's.
      theta.at<float>(r, c) = std::atan2(-grid.v.at<float>(r, c), grid.u.at<float>(r, c));
    }
  }

  const cv::Mat zero = cv::Mat::zeros(rows, cols, CV_32F);
  cv::Mat energy_even = zero.clone();  // EnergyV(:,:,1..3) of Kovesi's code
  cv::Mat energy_x = zero.clone();
  cv::Mat energy_y = zero.clone();
  cv::Mat cov_x2 = zero.clone();
  cv::Mat cov_y2 = zero.clone();
  cv::Mat cov_xy = zero.clone();
  const float eps = static_cast<float>(o.epsilon);

  std::vector<cv::Mat> eo(static_cast<std::size_t>(o.nscale));
  cv::Mat filter(rows, cols, CV_32F);
  cv::Mat product;
  for (int orient = 0; orient < o.norient; ++orient) {
    const double angle = orient * kPi / o.norient;
    const double cos_a = std::cos(angle);
    const double sin_a = std::sin(angle);
    cv::Mat spread(rows, cols, CV_32F);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const double t = theta.at<float>(r, c);
        const double ds = std::sin(t) * cos_a - std::cos(t) * sin_a;
        const double dc = std::cos(t) * cos_a + std::sin(t) * sin_a;
        const double dtheta = std::min(std::abs(std::atan2(ds, dc)) * o.norient / 2.0, kPi);
        spread.at<float>(r, c) = static_cast<float>((std::cos(dtheta) + 1.0) / 2.0);
      }
    }
    cv::Mat sum_e = zero.clone();
    cv::Mat sum_o = zero.clone();
    cv::Mat sum_an = zero.clone();
    cv::Mat max_an = zero.clone();
    double threshold = o.fixed_noise_threshold;
    for (int s = 0; s < o.nscale; ++s) {
      cv::multiply(log_gabor[static_cast<std::size_t>(s)], spread, filter);
      MultiplyByReal(image_fft, filter, product);
      cv::Mat& response = eo[static_cast<std::size_t>(s)];
      cv::dft(product, response, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_COMPLEX_OUTPUT);
      for (int r = 0; r < rows; ++r) {
        const float* e = response.ptr<float>(r);
        float* se = sum_e.ptr<float>(r);
        float* so = sum_o.ptr<float>(r);
        float* sa = sum_an.ptr<float>(r);
        float* ma = max_an.ptr<float>(r);
        for (int c = 0; c < cols; ++c) {
          const float amplitude = std::sqrt(e[2 * c] * e[2 * c] + e[2 * c + 1] * e[2 * c + 1]);
          se[c] += e[2 * c];
          so[c] += e[2 * c + 1];
          sa[c] += amplitude;
          ma[c] = std::max(ma[c], amplitude);
        }
      }
      if (s == 0 && o.fixed_noise_threshold < 0.0) {
        threshold = NoiseThreshold(Median(sum_an), o.nscale, o.mult, o.k);
      }
    }
    // Phase deviation energy of this orientation, noise-thresholded and weighted by the
    // spread of frequencies (Kovesi's PC_2 measure).
    const float weight_scale = 1.0f / static_cast<float>(o.nscale - 1);
    for (int r = 0; r < rows; ++r) {
      float* se = sum_e.ptr<float>(r);
      const float* so = sum_o.ptr<float>(r);
      const float* sa = sum_an.ptr<float>(r);
      const float* ma = max_an.ptr<float>(r);
      float* ev = energy_even.ptr<float>(r);
      float* ex = energy_x.ptr<float>(r);
      float* ey = energy_y.ptr<float>(r);
      float* cx2 = cov_x2.ptr<float>(r);
      float* cy2 = cov_y2.ptr<float>(r);
      float* cxy = cov_xy.ptr<float>(r);
      for (int c = 0; c < cols; ++c) {
        ev[c] += se[c];
        ex[c] += static_cast<float>(cos_a) * so[c];
        ey[c] += static_cast<float>(sin_a) * so[c];
        const float x_energy = std::sqrt(se[c] * se[c] + so[c] * so[c]) + eps;
        const float mean_e = se[c] / x_energy;
        const float mean_o = so[c] / x_energy;
        float energy = 0.0f;
        for (int s = 0; s < o.nscale; ++s) {
          const float* e = eo[static_cast<std::size_t>(s)].ptr<float>(r);
          const float even = e[2 * c];
          const float odd = e[2 * c + 1];
          energy += even * mean_e + odd * mean_o - std::abs(even * mean_o - odd * mean_e);
        }
        energy = std::max(energy - static_cast<float>(threshold), 0.0f);
        const float width = (sa[c] / (ma[c] + eps) - 1.0f) * weight_scale;
        const float weight =
            1.0f /
            (1.0f + std::exp((static_cast<float>(o.cut_off) - width) * static_cast<float>(o.g)));
        const float pc = weight * energy / (sa[c] + eps);
        const float cov_x = pc * static_cast<float>(cos_a);
        const float cov_y = pc * static_cast<float>(sin_a);
        cx2[c] += cov_x * cov_x;
        cy2[c] += cov_y * cov_y;
        cxy[c] += cov_x * cov_y;
      }
    }
  }

  PhaseCongruency result{cv::Mat(rows, cols, CV_32F), cv::Mat(rows, cols, CV_32F),
                         cv::Mat(rows, cols, CV_32F)};
  const float half_orient = static_cast<float>(o.norient) / 2.0f;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const float x2 = cov_x2.at<float>(r, c) / half_orient;
      const float y2 = cov_y2.at<float>(r, c) / half_orient;
      const float xy = 4.0f * cov_xy.at<float>(r, c) / static_cast<float>(o.norient);
      const float denom = std::sqrt(xy * xy + (x2 - y2) * (x2 - y2)) + eps;
      result.max_moment.at<float>(r, c) = std::clamp((y2 + x2 + denom) / 2.0f, 0.0f, 1.0f);
      result.min_moment.at<float>(r, c) = std::clamp((y2 + x2 - denom) / 2.0f, 0.0f, 1.0f);
      float angle = std::atan2(energy_y.at<float>(r, c), energy_x.at<float>(r, c));
      if (angle < 0.0f) angle += static_cast<float>(kPi);
      if (angle >= static_cast<float>(kPi)) angle = 0.0f;
      result.orientation.at<float>(r, c) = angle;
    }
  }
  return result;
}

// Scratch matrices of the fast variant for one call. Reused call after call: at a fixed size
// nothing is allocated, which saves the page faults of ~10 MB of fresh buffers per frame.
struct FastPhaseCongruency::Workspace {
  cv::Mat full;
  cv::Mat image;
  cv::Mat complex_image;
  cv::Mat image_fft;
  cv::Mat spectrum;
  cv::Mat packed;
  cv::Mat spare;
  std::vector<cv::Mat> even;
  std::vector<cv::Mat> odd;
  cv::Mat sum_an;
  cv::Mat max_an;
  cv::Mat sum_f;
  cv::Mat sum_h1;
  cv::Mat sum_h2;
  cv::Mat pc;
  cv::Mat orientation;
};

// The filter bank and FFT plans of the fast variant for one image size: per scale, the radial
// log-Gabor filter and its product with the Riesz kernel H = (i u - v) / |f|, both scaled by 1/N
// so that the inverse FFTs come out normalised.
struct FastPhaseCongruency::FilterCache {
  std::mutex mutex;
  cv::Size size;
  std::shared_ptr<const ComplexFft2d> fft;
  std::vector<cv::Mat> log_gabor;        // CV_32F
  std::vector<cv::Mat> log_gabor_riesz;  // CV_32FC2
};

// The workspaces no call is using. They belong to the instance, not to a thread: callers (the
// extractor) run each frame's edge map on a new thread, where buffers kept per thread would be
// allocated afresh every frame.
struct FastPhaseCongruency::WorkspacePool {
  std::mutex mutex;
  std::vector<std::unique_ptr<Workspace>> idle;
};

// A workspace taken from the pool (or a new one) for one call, and given back.
class FastPhaseCongruency::WorkspaceLease {
 public:
  explicit WorkspaceLease(WorkspacePool& pool) : pool_(pool) {
    std::lock_guard<std::mutex> lock(pool_.mutex);
    if (pool_.idle.empty()) {
      workspace_ = std::make_unique<Workspace>();
    } else {
      workspace_ = std::move(pool_.idle.back());
      pool_.idle.pop_back();
    }
  }
  ~WorkspaceLease() {
    std::lock_guard<std::mutex> lock(pool_.mutex);
    pool_.idle.push_back(std::move(workspace_));
  }
  WorkspaceLease(const WorkspaceLease&) = delete;
  WorkspaceLease& operator=(const WorkspaceLease&) = delete;

  Workspace& operator*() const { return *workspace_; }

 private:
  WorkspacePool& pool_;
  std::unique_ptr<Workspace> workspace_;
};

FastPhaseCongruency::FastPhaseCongruency(const FastPhaseCongruencyOptions& options)
    : options_(options),
      cache_(std::make_unique<FilterCache>()),
      workspaces_(std::make_unique<WorkspacePool>()) {
  options_.Check();
}

FastPhaseCongruency::~FastPhaseCongruency() = default;

PhaseCongruency FastPhaseCongruency::Compute(const cv::Mat& gray) const {
  if (options_.downscale == 1) return ComputeAtWorkingSize(gray);
  // The working-size results go to the scratch, since only their interpolation is returned.
  const WorkspaceLease lease(*workspaces_);
  Workspace& ws = *lease;
  ComputeInto(gray, ws, ws.pc, ws.orientation);
  PhaseCongruency result;
  cv::resize(ws.pc, result.max_moment, gray.size(), 0, 0, cv::INTER_LINEAR);
  cv::resize(ws.orientation, result.orientation, gray.size(), 0, 0, cv::INTER_NEAREST);
  return result;
}

PhaseCongruency FastPhaseCongruency::ComputeAtWorkingSize(const cv::Mat& gray) const {
  PhaseCongruency result;
  const WorkspaceLease lease(*workspaces_);
  ComputeInto(gray, *lease, result.max_moment, result.orientation);
  return result;
}

void FastPhaseCongruency::ComputeInto(const cv::Mat& gray, Workspace& ws, cv::Mat& pc,
                                      cv::Mat& orientation) const {
  const FastPhaseCongruencyOptions& o = options_;
  CheckGray(gray, kMinPhaseCongruencySize * o.downscale);
  gray.convertTo(ws.full, CV_32F);
  const cv::Mat& full = ws.full;
  if (o.downscale > 1) {
    cv::resize(full, ws.image, cv::Size(full.cols / o.downscale, full.rows / o.downscale), 0, 0,
               cv::INTER_AREA);
  } else {
    ws.image = full;
  }
  const cv::Mat& image = ws.image;
  const int rows = image.rows;
  const int cols = image.cols;
  const std::size_t nscale = static_cast<std::size_t>(o.nscale);

  std::shared_ptr<const ComplexFft2d> fft;
  std::vector<cv::Mat> log_gabor;
  std::vector<cv::Mat> log_gabor_riesz;
  {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    if (cache_->size != image.size()) {
      const FrequencyGrid grid = MakeGrid(rows, cols);
      const float inverse_n = 1.0f / static_cast<float>(rows * cols);
      cache_->log_gabor = MakeLogGabors(grid, o.nscale, o.min_wavelength / o.downscale, o.mult,
                                        o.sigma_on_f, o.lowpass_cutoff, o.lowpass_order);
      cache_->log_gabor_riesz.clear();
      for (cv::Mat& lg : cache_->log_gabor) {
        lg *= inverse_n;
        cv::Mat riesz(rows, cols, CV_32FC2);
        for (int r = 0; r < rows; ++r) {
          for (int c = 0; c < cols; ++c) {
            const float value = lg.at<float>(r, c) / grid.radius.at<float>(r, c);
            riesz.at<cv::Vec2f>(r, c) =
                cv::Vec2f(-grid.v.at<float>(r, c) * value, grid.u.at<float>(r, c) * value);
          }
        }
        cache_->log_gabor_riesz.push_back(riesz);
      }
      cache_->fft = std::make_shared<const ComplexFft2d>(image.size());
      cache_->size = image.size();
    }
    // Shallow copies: the matrices are never written after they are built.
    fft = cache_->fft;
    log_gabor = cache_->log_gabor;
    log_gabor_riesz = cache_->log_gabor_riesz;
  }

  cv::Mat& image_fft = ws.image_fft;
  {
    cv::Mat& complex_image = ws.complex_image;
    complex_image.create(rows, cols, CV_32FC2);
    for (int r = 0; r < rows; ++r) {
      const float* in = image.ptr<float>(r);
      float* out = complex_image.ptr<float>(r);
      for (int c = 0; c < cols; ++c) {
        out[2 * c] = in[c];
        out[2 * c + 1] = 0.0f;
      }
    }
    fft->Forward(complex_image, image_fft);
  }

  // Even responses f_s are real, so two scales share one inverse FFT (f_s + i f_{s+1});
  // the odd pair (h1, h2) of one scale comes out of one complex inverse FFT.
  std::vector<cv::Mat>& even = ws.even;
  even.resize(nscale);
  for (cv::Mat& e : even) e.create(rows, cols, CV_32F);
  cv::Mat& spectrum = ws.spectrum;
  spectrum.create(rows, cols, CV_32FC2);
  for (std::size_t s = 0; s < nscale; s += 2) {
    const bool pair = s + 1 < nscale;
    for (int r = 0; r < rows; ++r) {
      const float* in = image_fft.ptr<float>(r);
      const float* a = log_gabor[s].ptr<float>(r);
      const float* b = pair ? log_gabor[s + 1].ptr<float>(r) : nullptr;
      float* out = spectrum.ptr<float>(r);
      for (int c = 0; c < cols; ++c) {
        const float bv = pair ? b[c] : 0.0f;
        // (x a) + i (x b) for complex x = in.
        out[2 * c] = in[2 * c] * a[c] - in[2 * c + 1] * bv;
        out[2 * c + 1] = in[2 * c + 1] * a[c] + in[2 * c] * bv;
      }
    }
    fft->Inverse(spectrum, ws.packed);
    ws.spare.create(rows, cols, CV_32F);
    // Headers sharing the workspace's buffers: split writes in place.
    cv::Mat channels[2] = {even[s], pair ? even[s + 1] : ws.spare};
    cv::split(ws.packed, channels);
  }

  std::vector<cv::Mat>& odd = ws.odd;
  odd.resize(nscale);
  cv::Mat& sum_an = ws.sum_an;
  cv::Mat& max_an = ws.max_an;
  cv::Mat& sum_f = ws.sum_f;
  cv::Mat& sum_h1 = ws.sum_h1;
  cv::Mat& sum_h2 = ws.sum_h2;
  for (cv::Mat* sum : {&sum_an, &max_an, &sum_f, &sum_h1, &sum_h2}) Zeros(*sum, rows, cols);
  double threshold = o.fixed_noise_threshold;
  for (std::size_t s = 0; s < nscale; ++s) {
    // spectrum = image_fft * riesz (complex, element-wise): cv::mulSpectrums costs 4x this loop.
    for (int r = 0; r < rows; ++r) {
      const float* x = image_fft.ptr<float>(r);
      const float* h = log_gabor_riesz[s].ptr<float>(r);
      float* out = spectrum.ptr<float>(r);
      for (int c = 0; c < 2 * cols; c += 2) {
        out[c] = x[c] * h[c] - x[c + 1] * h[c + 1];
        out[c + 1] = x[c] * h[c + 1] + x[c + 1] * h[c];
      }
    }
    fft->Inverse(spectrum, odd[s]);
    for (int r = 0; r < rows; ++r) {
      const float* h = odd[s].ptr<float>(r);
      const float* f = even[s].ptr<float>(r);
      float* sa = sum_an.ptr<float>(r);
      float* ma = max_an.ptr<float>(r);
      float* sf = sum_f.ptr<float>(r);
      float* sh1 = sum_h1.ptr<float>(r);
      float* sh2 = sum_h2.ptr<float>(r);
      int c = 0;
#if CV_SIMD
      // The same operations in the same order as the scalar loop below, so results are identical.
      constexpr int kLanes = cv::v_float32::nlanes;
      for (; c + kLanes <= cols; c += kLanes) {
        const cv::v_float32 fv = cv::vx_load(f + c);
        cv::v_float32 h1;
        cv::v_float32 h2;
        cv::v_load_deinterleave(h + 2 * c, h1, h2);
        const cv::v_float32 an = cv::v_sqrt(fv * fv + h1 * h1 + h2 * h2);
        cv::v_store(sa + c, cv::vx_load(sa + c) + an);
        cv::v_store(ma + c, cv::v_max(cv::vx_load(ma + c), an));
        cv::v_store(sf + c, cv::vx_load(sf + c) + fv);
        cv::v_store(sh1 + c, cv::vx_load(sh1 + c) + h1);
        cv::v_store(sh2 + c, cv::vx_load(sh2 + c) + h2);
      }
#endif
      for (; c < cols; ++c) {
        const float an = std::sqrt(f[c] * f[c] + h[2 * c] * h[2 * c] + h[2 * c + 1] * h[2 * c + 1]);
        sa[c] += an;
        ma[c] = std::max(ma[c], an);
        sf[c] += f[c];
        sh1[c] += h[2 * c];
        sh2[c] += h[2 * c + 1];
      }
    }
    if (s == 0 && o.fixed_noise_threshold < 0.0) {
      threshold = NoiseThreshold(Median(sum_an), o.nscale, o.mult, o.k);
    }
  }

  pc.create(rows, cols, CV_32F);
  orientation.create(rows, cols, CV_32F);
  const float eps = static_cast<float>(o.epsilon);
  const float weight_scale = 1.0f / static_cast<float>(o.nscale - 1);
  const float t = static_cast<float>(threshold);
  const float cut_off = static_cast<float>(o.cut_off);
  const float g = static_cast<float>(o.g);
  const float gain = static_cast<float>(o.deviation_gain);
  // The frequency-spread weight as a table over width in [0, 1] (width never leaves it): the
  // sigmoid is smooth, so 1024 steps are far below any threshold's resolution.
  constexpr int kWeightBins = 1024;
  std::vector<float> weight_table(kWeightBins);
  for (int i = 0; i < kWeightBins; ++i) {
    const float width = static_cast<float>(i) / static_cast<float>(kWeightBins - 1);
    weight_table[static_cast<std::size_t>(i)] = 1.0f / (1.0f + std::exp((cut_off - width) * g));
  }
  std::vector<float> negated_h2(static_cast<std::size_t>(cols));
  std::vector<const float*> f_rows(nscale);
  std::vector<const float*> h_rows(nscale);
  for (int r = 0; r < rows; ++r) {
    const float* sa = sum_an.ptr<float>(r);
    const float* ma = max_an.ptr<float>(r);
    const float* sf = sum_f.ptr<float>(r);
    const float* sh1 = sum_h1.ptr<float>(r);
    const float* sh2 = sum_h2.ptr<float>(r);
    for (std::size_t s = 0; s < nscale; ++s) {
      f_rows[s] = even[s].ptr<float>(r);
      h_rows[s] = odd[s].ptr<float>(r);
    }
    float* out = pc.ptr<float>(r);
    float* angle = orientation.ptr<float>(r);
    // The arc tangent of the whole row at once (vectorised); below the noise threshold the
    // orientation is then set to 0.
    for (int i = 0; i < cols; ++i) negated_h2[static_cast<std::size_t>(i)] = -sh2[i];
    cv::hal::fastAtan32f(negated_h2.data(), sh1, angle, cols, /*angleInDegrees=*/true);
    int c = 0;
#if CV_SIMD
    // phasecong3's measure on whole vectors: the scalar loop's operations in its order, so the
    // values are the same; only the weight table is read lane by lane.
    if (o.measure == FastPhaseCongruencyOptions::Measure::kEnergyDeviation) {
      constexpr int kLanes = cv::v_float32::nlanes;
      const cv::v_float32 v_t = cv::vx_setall_f32(t);
      const cv::v_float32 v_eps = cv::vx_setall_f32(eps);
      const cv::v_float32 v_zero = cv::vx_setzero_f32();
      const cv::v_float32 v_one = cv::vx_setall_f32(1.0f);
      const cv::v_float32 v_weight_scale = cv::vx_setall_f32(weight_scale);
      const cv::v_float32 v_last_bin = cv::vx_setall_f32(static_cast<float>(kWeightBins - 1));
      const cv::v_float32 v_half = cv::vx_setall_f32(0.5f);
      const cv::v_float32 v_pi = cv::vx_setall_f32(static_cast<float>(kPi));
      const cv::v_float32 v_to_radians = cv::vx_setall_f32(static_cast<float>(kPi) / 180.0f);
      alignas(64) int bins[kLanes];
      alignas(64) float weights[kLanes];
      for (; c + kLanes <= cols; c += kLanes) {
        const cv::v_float32 sfv = cv::vx_load(sf + c);
        const cv::v_float32 s1 = cv::vx_load(sh1 + c);
        const cv::v_float32 s2 = cv::vx_load(sh2 + c);
        const cv::v_float32 energy = cv::v_sqrt(sfv * sfv + s1 * s1 + s2 * s2);
        const cv::v_float32 above = energy > v_t;
        if (cv::v_signmask(above) == 0) {
          cv::v_store(out + c, v_zero);
          cv::v_store(angle + c, v_zero);
          continue;
        }
        const cv::v_float32 sav = cv::vx_load(sa + c);
        const cv::v_float32 width = (sav / (cv::vx_load(ma + c) + v_eps) - v_one) * v_weight_scale;
        cv::v_store(bins,
                    cv::v_trunc(cv::v_min(cv::v_max(width, v_zero), v_one) * v_last_bin + v_half));
        for (int lane = 0; lane < kLanes; ++lane) {
          weights[lane] = weight_table[static_cast<std::size_t>(bins[lane])];
        }
        const cv::v_float32 inv = v_one / (energy + v_eps);
        const cv::v_float32 mf = sfv * inv;
        const cv::v_float32 m1 = s1 * inv;
        const cv::v_float32 m2 = s2 * inv;
        cv::v_float32 sum = v_zero;
        for (std::size_t s = 0; s < nscale; ++s) {
          const cv::v_float32 f = cv::vx_load(f_rows[s] + c);
          cv::v_float32 h1;
          cv::v_float32 h2;
          cv::v_load_deinterleave(h_rows[s] + 2 * c, h1, h2);
          const cv::v_float32 along = f * mf + h1 * m1 + h2 * m2;
          const cv::v_float32 an2 = f * f + h1 * h1 + h2 * h2;
          sum = sum + (along - cv::v_sqrt(cv::v_max(an2 - along * along, v_zero)));
        }
        const cv::v_float32 value =
            cv::vx_load(weights) * cv::v_max(sum - v_t, v_zero) / (sav + v_eps);
        cv::v_store(out + c,
                    cv::v_select(above, cv::v_min(cv::v_max(value, v_zero), v_one), v_zero));
        cv::v_float32 normal = cv::vx_load(angle + c) * v_to_radians;
        normal = cv::v_select(normal >= v_pi, normal - v_pi, normal);
        normal = cv::v_select(normal >= v_pi, v_zero, normal);
        cv::v_store(angle + c, cv::v_select(above, normal, v_zero));
      }
    }
#endif
    for (; c < cols; ++c) {
      const float energy = std::sqrt(sf[c] * sf[c] + sh1[c] * sh1[c] + sh2[c] * sh2[c]);
      // Both measures are 0 at or below the noise threshold (the deviation sum never exceeds
      // the energy), which is most of a frame: skip the transcendental work there.
      if (energy <= t) {
        out[c] = 0.0f;
        angle[c] = 0.0f;
        continue;
      }
      const float width = (sa[c] / (ma[c] + eps) - 1.0f) * weight_scale;
      const float weight = weight_table[static_cast<std::size_t>(
          std::clamp(width, 0.0f, 1.0f) * static_cast<float>(kWeightBins - 1) + 0.5f)];
      float value = 0.0f;
      if (o.measure == FastPhaseCongruencyOptions::Measure::kArcCosine) {
        const float cosine = std::min(energy / (sa[c] + eps), 1.0f);
        const float deviation = std::max(1.0f - gain * std::acos(cosine), 0.0f);
        value = weight * deviation * (energy - t) / (energy + eps);
      } else {
        // phasecong3's measure, with the monogenic vector in place of the even/odd pair: each
        // scale adds A cos(d) - A |sin(d)|, d its angle from the mean phase vector.
        const float inv = 1.0f / (energy + eps);
        const float mf = sf[c] * inv;
        const float m1 = sh1[c] * inv;
        const float m2 = sh2[c] * inv;
        float sum = 0.0f;
        for (std::size_t s = 0; s < nscale; ++s) {
          const float f = f_rows[s][c];
          const float h1 = h_rows[s][2 * c];
          const float h2 = h_rows[s][2 * c + 1];
          const float along = f * mf + h1 * m1 + h2 * m2;
          const float an2 = f * f + h1 * h1 + h2 * h2;
          sum += along - std::sqrt(std::max(an2 - along * along, 0.0f));
        }
        value = weight * std::max(sum - t, 0.0f) / (sa[c] + eps);
      }
      out[c] = std::clamp(value, 0.0f, 1.0f);
      angle[c] = NormalFromDegrees(angle[c]);
    }
  }
}

}  // namespace noctua::edges
