#pragma once

#include <memory>
#include <opencv2/core.hpp>

namespace noctua::edges {

// Parameters of Kovesi's phasecong3 (log-Gabor filter bank in the frequency domain). The
// defaults are Kovesi's (and the paper's); the noise threshold is estimated from the image.
struct PhaseCongruencyOptions {
  int nscale = 4;                // number of wavelet scales
  int norient = 6;               // number of filter orientations
  double min_wavelength = 3.0;   // wavelength of the smallest-scale filter, pixels
  double mult = 2.1;             // wavelength ratio of successive scales
  double sigma_on_f = 0.55;      // log-Gabor bandwidth: sigma of the Gaussian over the centre
  double lowpass_cutoff = 0.45;  // low-pass filter applied to every log-Gabor filter: cut-off
  int lowpass_order = 15;        // ...and order (keeps the corners of the spectrum out)
  double k = 2.0;                // noise threshold in standard deviations of the noise energy
  double cut_off = 0.5;          // frequency-spread fraction below which PC is penalised
  double g = 10.0;               // sharpness of that sigmoid penalty
  double epsilon = 1e-4;         // avoids division by zero on flat regions
  // Noise threshold: < 0 estimates it from the median amplitude of the smallest scale
  // (Rayleigh statistics, Kovesi's noiseMethod -1); >= 0 uses this fixed energy value.
  double fixed_noise_threshold = -1.0;

  // Throws noctua::Error naming the first invalid field.
  void Check() const;
};

// The outputs of phasecong3 that noctua uses, all CV_32F of the input's size.
struct PhaseCongruency {
  cv::Mat max_moment;   // M: maximum moment of PC covariance, in [0, 1]; the edge strength
  cv::Mat min_moment;   // m: minimum moment, in [0, 1]; large at corners
  cv::Mat orientation;  // feature normal, radians in [0, pi), anticlockwise, 0 = along +x
};

// The smallest image phase congruency accepts on either side; below this the filter bank's
// smallest wavelengths no longer fit.
inline constexpr int kMinPhaseCongruencySize = 16;

// The reference: phasecong3 on an 8-bit (or float) single-channel image, with plain
// (periodic) FFTs as in Kovesi's code. Throws noctua::Error for empty, multi-channel or smaller
// than kMinPhaseCongruencySize images.
PhaseCongruency ComputePhaseCongruency(const cv::Mat& gray,
                                       const PhaseCongruencyOptions& options = {});

// Parameters of the fast variant: Kovesi's phasecongmono (monogenic signal: one forward FFT and,
// here, 1.5 inverse FFTs per scale instead of norient), optionally on a reduced-resolution
// image, with the filters cached per image size.
struct FastPhaseCongruencyOptions {
  int nscale = 4;
  // In pixels of the full-resolution image (the filters on the reduced image use
  // min_wavelength / downscale), so that the scales match the reference's.
  double min_wavelength = 3.0;
  double mult = 2.1;
  double sigma_on_f = 0.55;
  double lowpass_cutoff = 0.45;
  int lowpass_order = 15;
  double k = 2.0;  // same noise threshold as the reference, so that both agree
  double cut_off = 0.5;
  double g = 10.0;
  // How phase deviation turns energy into PC: kEnergyDeviation is phasecong3's
  // sum of A cos(d) - A |sin(d)| over scales (agrees best with the reference, docs/edges.md);
  // kArcCosine is phasecongmono's 1 - deviation_gain * acos(E / sum A).
  enum class Measure { kEnergyDeviation, kArcCosine };
  Measure measure = Measure::kEnergyDeviation;
  double deviation_gain = 1.5;  // for kArcCosine
  double epsilon = 1e-4;
  double fixed_noise_threshold = -1.0;
  // 1 = full resolution; 2 = filters run on the image halved in each direction and PC is
  // brought back to full size (4x fewer FFT points). Chosen by measurement, docs/edges.md.
  int downscale = 2;

  void Check() const;
};

// The fast variant. Holds the filter bank and FFT plans for the last image size; thread-safe
// (the cache is guarded), so one instance can serve an extractor used from several threads.
// The instance keeps the scratch buffers (about 10 MB at 640x480) of its calls for reuse, one
// set per call running at the same time, whichever thread makes the call.
class FastPhaseCongruency {
 public:
  explicit FastPhaseCongruency(const FastPhaseCongruencyOptions& options = {});
  ~FastPhaseCongruency();
  FastPhaseCongruency(const FastPhaseCongruency&) = delete;
  FastPhaseCongruency& operator=(const FastPhaseCongruency&) = delete;

  // PC (as max_moment; min_moment is left empty: the monogenic signal has no per-orientation
  // moments) and orientation at the input's full size. Same input rules as the reference;
  // with downscale the input must be at least downscale * kMinPhaseCongruencySize on each side.
  PhaseCongruency Compute(const cv::Mat& gray) const;

  // The same at the working size (the input's size divided by downscale, rounded down), before
  // it is brought back to full size: what an edge map at that size needs, without the cost of
  // interpolating PC and orientation to every full-size pixel.
  PhaseCongruency ComputeAtWorkingSize(const cv::Mat& gray) const;

  const FastPhaseCongruencyOptions& options() const { return options_; }

 private:
  struct FilterCache;
  struct Workspace;
  struct WorkspacePool;
  class WorkspaceLease;
  // Writes PC and orientation at the working size into the given matrices (allocated as needed),
  // with `ws` as scratch.
  void ComputeInto(const cv::Mat& gray, Workspace& ws, cv::Mat& pc, cv::Mat& orientation) const;

  FastPhaseCongruencyOptions options_;
  std::unique_ptr<FilterCache> cache_;
  std::unique_ptr<WorkspacePool> workspaces_;
};

}  // namespace noctua::edges
