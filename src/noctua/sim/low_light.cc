#include "noctua/sim/low_light.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "noctua/util/error.h"

namespace noctua::sim {

void SensorModel::Check() const {
  CheckOption(gamma > 0.0 && std::isfinite(gamma), "sensor gamma must be positive");
  CheckOption(full_well_electrons >= 1.0 && std::isfinite(full_well_electrons),
              "sensor full_well_electrons must be at least 1");
  CheckOption(read_noise_electrons >= 0.0 && std::isfinite(read_noise_electrons),
              "sensor read_noise_electrons must be non-negative");
}

LowLightSimulator::LowLightSimulator(const SensorModel& model, double brightness)
    : model_(model), brightness_(brightness) {
  model_.Check();
  CheckOption(brightness > 0.0 && brightness <= 1.0,
              "low-light brightness factor must be in (0, 1], got " + std::to_string(brightness));
  ComputeMoments();
}

double LowLightSimulator::ExpectedElectrons(double value8u) const {
  return brightness_ * std::pow(value8u / 255.0, model_.gamma) * model_.full_well_electrons;
}

double LowLightSimulator::ElectronVariance(double value8u) const {
  return ExpectedElectrons(value8u) + model_.read_noise_electrons * model_.read_noise_electrons;
}

LowLightSimulator::Moments LowLightSimulator::ExpectedOutput(int value8u) const {
  CheckOption(value8u >= 0 && value8u <= 255, "8-bit value out of range");
  return moments_[static_cast<std::size_t>(value8u)];
}

void LowLightSimulator::ComputeMoments() {
  // Output q is reached when the electron count e passes t_q = FW ((q - 0.5) / 255)^gamma, so
  // E[out | k] = sum_q P(e >= t_q) and E[out^2 | k] = sum_q (2q - 1) P(e >= t_q), e ~ N(k, s^2);
  // then a Poisson-weighted sum over the photo-electron count k.
  const double full_well = model_.full_well_electrons;
  const double sigma = model_.read_noise_electrons;
  std::vector<double> thresholds(256, 0.0);  // thresholds[0] unused
  for (int q = 1; q <= 255; ++q) {
    thresholds[q] = full_well * std::pow((q - 0.5) / 255.0, model_.gamma);
  }
  const double reach = 9.0 * sigma;
  auto conditional = [&](double k) {
    // q below q_first are certain (P = 1): sum of 1 is n, sum of (2q - 1) is n^2.
    const int q_first = static_cast<int>(
        std::lower_bound(thresholds.begin() + 1, thresholds.end(), k - reach) - thresholds.begin());
    Moments m;
    m.mean = q_first - 1.0;
    m.variance = (q_first - 1.0) * (q_first - 1.0);  // holds E[out^2] here
    for (int q = q_first; q <= 255 && thresholds[q] <= k + reach; ++q) {
      const double p_above = sigma > 0.0
                                 ? 0.5 * std::erfc((thresholds[q] - k) / (sigma * std::sqrt(2.0)))
                                 : (k >= thresholds[q] ? 1.0 : 0.0);
      m.mean += p_above;
      m.variance += (2.0 * q - 1.0) * p_above;
    }
    return m;
  };
  const double max_mu = brightness_ * full_well;
  const long k_max = static_cast<long>(std::ceil(max_mu + 10.0 * std::sqrt(max_mu) + 10.0));
  std::vector<Moments> given_k(static_cast<std::size_t>(k_max) + 1);
  for (long k = 0; k <= k_max; ++k) given_k[static_cast<std::size_t>(k)] = conditional(k);
  for (int v = 0; v < 256; ++v) {
    const double mu = ExpectedElectrons(v);
    double sum1 = given_k[0].mean;
    double sum2 = given_k[0].variance;
    if (mu > 0.0) {
      const double spread = 10.0 * std::sqrt(mu) + 10.0;
      const long k_lo = std::max(0L, static_cast<long>(std::floor(mu - spread)));
      const long k_hi = std::min(k_max, static_cast<long>(std::ceil(mu + spread)));
      double total = 0.0;
      sum1 = sum2 = 0.0;
      for (long k = k_lo; k <= k_hi; ++k) {
        const double p = std::exp(k * std::log(mu) - mu - std::lgamma(k + 1.0));
        const Moments& m = given_k[static_cast<std::size_t>(k)];
        sum1 += p * m.mean;
        sum2 += p * m.variance;
        total += p;
      }
      sum1 /= total;
      sum2 /= total;
    }
    moments_[static_cast<std::size_t>(v)] = {sum1, sum2 - sum1 * sum1};
  }
}

cv::Mat LowLightSimulator::Apply(const cv::Mat& image8u, cv::RNG& rng) const {
  if (image8u.empty() || image8u.depth() != CV_8U ||
      (image8u.channels() != 1 && image8u.channels() != 3 && image8u.channels() != 4)) {
    throw Error("low-light simulation needs an 8-bit grey, BGR or BGRA image");
  }
  // std::poisson_distribution needs a URNG; seed it from the caller's cv::RNG so that one seed
  // fixes the whole sequence.
  std::mt19937_64 engine(static_cast<std::uint64_t>(rng.next()) << 32 | rng.next());
  std::normal_distribution<double> read_noise(0.0, model_.read_noise_electrons);
  // One distribution per input value: the mean depends on nothing else.
  // Shot noise per input value. Below kExactMean electrons the Poisson count is drawn exactly by
  // inverting its cumulative distribution (a table per value); above, by the normal distribution
  // of the same mean and variance, whose skew (1 / sqrt(mean) < 0.1) is far below what 8-bit
  // output can show. std::poisson_distribution per pixel was 5x slower.
  constexpr double kExactMean = 100.0;
  std::vector<std::vector<double>> cdf(256);
  std::vector<double> means(256);
  for (int v = 0; v < 256; ++v) {
    const double mean = ExpectedElectrons(v);
    means[static_cast<std::size_t>(v)] = mean;
    if (mean >= kExactMean || mean <= 0.0) continue;
    std::vector<double>& table = cdf[static_cast<std::size_t>(v)];
    double p = std::exp(-mean), total = p;
    table.push_back(total);
    for (long k = 1; total < 1.0 - 1e-12 && k < 1000; ++k) {
      p *= mean / static_cast<double>(k);
      total += p;
      table.push_back(total);
    }
  }
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> unit_normal(0.0, 1.0);
  auto shot = [&](uchar value) -> double {
    const double mean = means[value];
    if (mean <= 0.0) return 0.0;
    if (mean >= kExactMean) return std::round(mean + std::sqrt(mean) * unit_normal(engine));
    const std::vector<double>& table = cdf[value];
    const double u = uniform(engine);
    return static_cast<double>(std::lower_bound(table.begin(), table.end(), u) - table.begin());
  };
  const double inv_full_well = 1.0 / model_.full_well_electrons;
  const double inv_gamma = 1.0 / model_.gamma;
  // The 8-bit output of a (possibly negative) electron count, through a table for speed: the
  // count is rounded to 1/16 e-, far below the read noise.
  constexpr int kSteps = 16;
  const int max_count = static_cast<int>(std::ceil(model_.full_well_electrons)) * kSteps;
  std::vector<uchar> encode(static_cast<std::size_t>(max_count) + 1);
  for (int i = 0; i <= max_count; ++i) {
    const double linear = std::min(1.0, i / static_cast<double>(kSteps) * inv_full_well);
    encode[static_cast<std::size_t>(i)] =
        cv::saturate_cast<uchar>(std::lround(255.0 * std::pow(linear, inv_gamma)));
  }
  const int channels = image8u.channels();
  const int noisy_channels = channels == 4 ? 3 : channels;
  cv::Mat out(image8u.size(), image8u.type());
  for (int y = 0; y < image8u.rows; ++y) {
    const uchar* src = image8u.ptr<uchar>(y);
    uchar* dst = out.ptr<uchar>(y);
    for (int x = 0; x < image8u.cols; ++x) {
      for (int c = 0; c < channels; ++c) {
        const int i = x * channels + c;
        if (c >= noisy_channels) {
          dst[i] = src[i];
          continue;
        }
        double electrons = shot(src[i]);
        if (model_.read_noise_electrons > 0.0) electrons += read_noise(engine);
        const long index = std::lround(electrons * kSteps);
        dst[i] = encode[static_cast<std::size_t>(std::clamp<long>(index, 0, max_count))];
      }
    }
  }
  return out;
}

double BrightnessForMeanRatio(const cv::Mat& reference, double mean_ratio,
                              const SensorModel& model) {
  CheckOption(mean_ratio > 0.0 && mean_ratio <= 1.0,
              "low-light level (mean grey ratio) must be in (0, 1]");
  if (reference.empty() || reference.depth() != CV_8U) {
    throw Error("low-light calibration needs an 8-bit reference frame");
  }
  // Histogram of all colour samples, so the mean of any tone curve is a 256-term sum.
  cv::Mat flat = reference.reshape(1, 1);
  std::vector<double> histogram(256, 0.0);
  for (int i = 0; i < flat.cols; ++i) histogram[flat.at<uchar>(0, i)] += 1.0;
  double original_mean = 0.0;
  for (int v = 0; v < 256; ++v) original_mean += v * histogram[v];
  original_mean /= flat.cols;
  if (original_mean < 0.5) throw Error("low-light calibration: the reference frame is black");
  auto mean_for = [&](double brightness) {
    const LowLightSimulator simulator(model, brightness);
    double sum = 0.0;
    for (int v = 0; v < 256; ++v) {
      if (histogram[v] > 0.0) sum += histogram[v] * simulator.ExpectedOutput(v).mean;
    }
    return sum / flat.cols / original_mean;
  };
  // The mean ratio grows monotonically with the light factor: bisect on a log scale.
  double lo = 1e-5;
  double hi = 1.0;
  for (int iteration = 0; iteration < 24; ++iteration) {
    const double mid = std::sqrt(lo * hi);
    (mean_for(mid) < mean_ratio ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

}  // namespace noctua::sim
