#include "noctua/sim/low_light.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "noctua/util/error.h"

namespace noctua::sim {

LowLightSimulator::LowLightSimulator(const SensorModel& model, double brightness)
    : model_(model), brightness_(brightness), exposure_s_(0.0) {
  model_.Check();
  CheckOption(brightness > 0.0 && brightness <= 1.0,
              "low-light brightness factor must be in (0, 1], got " + std::to_string(brightness));
  // Less light than the input's is only reached at the longest exposure (SensorModel).
  exposure_s_ = model_.ExposureForLevel(brightness);
  ComputeMoments();
}

double LowLightSimulator::ExpectedElectrons(double value8u) const {
  return brightness_ * std::pow(value8u / 255.0, model_.gamma) * model_.full_well_electrons;
}

double LowLightSimulator::GaussianVariance(double electrons) const {
  const SensorModel& m = model_;
  const double prnu = m.prnu * electrons;
  return m.read_noise_electrons * m.read_noise_electrons + m.dark_current_e_per_s * exposure_s_ +
         m.dsnu_electrons * m.dsnu_electrons + m.row_noise_electrons * m.row_noise_electrons +
         prnu * prnu;
}

double LowLightSimulator::ElectronVariance(double value8u) const {
  const double mean = ExpectedElectrons(value8u);
  return (model_.shot_noise ? mean : 0.0) + GaussianVariance(mean);
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
  std::vector<double> thresholds(256, 0.0);  // thresholds[0] unused
  for (int q = 1; q <= 255; ++q) {
    thresholds[q] = full_well * std::pow((q - 0.5) / 255.0, model_.gamma);
  }
  auto conditional = [&](double k) {
    const double sigma = std::sqrt(GaussianVariance(k));
    const double reach = 9.0 * sigma;
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
  if (!model_.shot_noise) {
    for (int v = 0; v < 256; ++v) {
      const Moments m = conditional(ExpectedElectrons(v));
      moments_[static_cast<std::size_t>(v)] = {m.mean, m.variance - m.mean * m.mean};
    }
    return;
  }
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

namespace {

// Draws the photo-electron count of each input value. Below kExactMean electrons the Poisson
// count is drawn exactly by inverting its cumulative distribution (a table per value); above, by
// the normal distribution of the same mean and variance, whose skew (1 / sqrt(mean) < 0.1) is far
// below what 8-bit output can show. std::poisson_distribution per pixel was 5x slower.
class ShotNoise {
 public:
  ShotNoise(const LowLightSimulator& simulator, bool noisy) : noisy_(noisy) {
    for (int v = 0; v < 256; ++v) {
      const double mean = simulator.ExpectedElectrons(v);
      means_[static_cast<std::size_t>(v)] = mean;
      if (!noisy || mean >= kExactMean || mean <= 0.0) continue;
      std::vector<double>& table = cdf_[static_cast<std::size_t>(v)];
      double p = std::exp(-mean), total = p;
      table.push_back(total);
      for (long k = 1; total < 1.0 - 1e-12 && k < 1000; ++k) {
        p *= mean / static_cast<double>(k);
        total += p;
        table.push_back(total);
      }
    }
  }

  double Draw(uchar value, std::mt19937_64& engine) {
    const double mean = means_[value];
    if (!noisy_ || mean <= 0.0) return mean;
    if (mean >= kExactMean) return std::round(mean + std::sqrt(mean) * unit_normal_(engine));
    const std::vector<double>& table = cdf_[value];
    const double u = uniform_(engine);
    return static_cast<double>(std::lower_bound(table.begin(), table.end(), u) - table.begin());
  }

 private:
  static constexpr double kExactMean = 100.0;
  bool noisy_;
  std::array<double, 256> means_{};
  std::array<std::vector<double>, 256> cdf_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::normal_distribution<double> unit_normal_{0.0, 1.0};
};

// The 8-bit output of a (possibly negative) electron count, through a table for speed: the count
// is rounded to 1/16 e-, far below the read noise.
class Encoder {
 public:
  explicit Encoder(const SensorModel& model)
      : max_index_(static_cast<long>(std::ceil(model.full_well_electrons)) * kSteps),
        table_(static_cast<std::size_t>(max_index_) + 1) {
    for (long i = 0; i <= max_index_; ++i) {
      const double linear =
          std::min(1.0, i / static_cast<double>(kSteps) / model.full_well_electrons);
      table_[static_cast<std::size_t>(i)] =
          cv::saturate_cast<uchar>(std::lround(255.0 * std::pow(linear, 1.0 / model.gamma)));
    }
  }
  uchar operator()(double electrons) const {
    const long index = std::clamp<long>(std::lround(electrons * kSteps), 0, max_index_);
    return table_[static_cast<std::size_t>(index)];
  }

 private:
  static constexpr int kSteps = 16;
  long max_index_;
  std::vector<uchar> table_;
};

// JPEG round trip at `quality`; the alpha of a BGRA frame is kept as it was.
cv::Mat CompressJpeg(const cv::Mat& image, int quality) {
  cv::Mat colour = image;
  if (image.channels() == 4) cv::cvtColor(image, colour, cv::COLOR_BGRA2BGR);
  std::vector<uchar> bytes;
  cv::imencode(".jpg", colour, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  cv::Mat decoded =
      cv::imdecode(bytes, colour.channels() == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  if (image.channels() != 4) return decoded;
  std::vector<cv::Mat> planes;
  cv::split(decoded, planes);
  cv::Mat alpha;
  cv::extractChannel(image, alpha, 3);
  planes.push_back(alpha);
  cv::merge(planes, decoded);
  return decoded;
}

std::uint64_t NameHash(const std::string& name) {
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a: stable across platforms
  for (const char c : name) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return hash;
}

}  // namespace

cv::Mat LowLightSimulator::FixedPattern(cv::Size size, int channels, double sigma,
                                        std::uint64_t salt) const {
  cv::Mat pattern(size.height, size.width * channels, CV_32F, cv::Scalar(0));
  if (sigma <= 0.0) return pattern;
  // Fixed: seeded by the model and the image size only, so every frame of a sequence shares it.
  cv::RNG rng(
      NameHash(model_.name) ^ salt ^
      (static_cast<std::uint64_t>(size.width) << 20 | static_cast<std::uint64_t>(size.height)));
  rng.fill(pattern, cv::RNG::NORMAL, 0.0, sigma);
  return pattern;
}

cv::Mat LowLightSimulator::Apply(const cv::Mat& image8u, cv::RNG& rng) const {
  if (image8u.empty() || image8u.depth() != CV_8U ||
      (image8u.channels() != 1 && image8u.channels() != 3 && image8u.channels() != 4)) {
    throw Error("low-light simulation needs an 8-bit grey, BGR or BGRA image");
  }
  const int channels = image8u.channels();
  if (!model_.shot_noise && GaussianVariance(model_.full_well_electrons) == 0.0) {
    // Without noise the output is a function of the input value: exact, through a table.
    cv::Mat table(1, 256, CV_8U);
    for (int v = 0; v < 256; ++v) {
      const double linear = std::min(1.0, ExpectedElectrons(v) / model_.full_well_electrons);
      table.at<uchar>(v) =
          cv::saturate_cast<uchar>(std::lround(255.0 * std::pow(linear, 1.0 / model_.gamma)));
    }
    cv::Mat out;
    cv::LUT(image8u, table, out);
    if (channels == 4)
      image8u.forEach<cv::Vec4b>(
          [&](const cv::Vec4b& p, const int* at) { out.at<cv::Vec4b>(at[0], at[1])[3] = p[3]; });
    return model_.jpeg_quality > 0 ? CompressJpeg(out, model_.jpeg_quality) : out;
  }
  // std::normal_distribution needs a URNG; seed it from the caller's cv::RNG so that one seed
  // fixes the whole sequence.
  std::mt19937_64 engine(static_cast<std::uint64_t>(rng.next()) << 32 | rng.next());
  const double temporal_sigma =
      std::sqrt(model_.read_noise_electrons * model_.read_noise_electrons +
                model_.dark_current_e_per_s * exposure_s_);
  std::normal_distribution<double> temporal(0.0, temporal_sigma > 0.0 ? temporal_sigma : 1.0);
  std::normal_distribution<double> row_noise(0.0, std::max(model_.row_noise_electrons, 1e-12));
  ShotNoise shot(*this, model_.shot_noise);
  const Encoder encode(model_);
  const int noisy_channels = channels == 4 ? 3 : channels;
  const cv::Mat gain = FixedPattern(image8u.size(), channels, model_.prnu, 0x9e3779b9ULL);
  const cv::Mat offset =
      FixedPattern(image8u.size(), channels, model_.dsnu_electrons, 0x85ebca6bULL);
  cv::Mat out(image8u.size(), image8u.type());
  for (int y = 0; y < image8u.rows; ++y) {
    const uchar* src = image8u.ptr<uchar>(y);
    const float* gain_row = gain.ptr<float>(y);
    const float* offset_row = offset.ptr<float>(y);
    uchar* dst = out.ptr<uchar>(y);
    const double row = model_.row_noise_electrons > 0.0 ? row_noise(engine) : 0.0;
    for (int x = 0; x < image8u.cols; ++x) {
      for (int c = 0; c < channels; ++c) {
        const int i = x * channels + c;
        if (c >= noisy_channels) {
          dst[i] = src[i];
          continue;
        }
        double electrons = shot.Draw(src[i], engine) * (1.0 + gain_row[i]) + offset_row[i] + row;
        if (temporal_sigma > 0.0) electrons += temporal(engine);
        dst[i] = encode(electrons);
      }
    }
  }
  return model_.jpeg_quality > 0 ? CompressJpeg(out, model_.jpeg_quality) : out;
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

LowLightSimulator SimulatorForLevel(const cv::Mat& reference, double level,
                                    const SensorModel& model) {
  return LowLightSimulator(model, BrightnessForMeanRatio(reference, level, model));
}

cv::Mat DarkenToLevel(const cv::Mat& image, double level, const SensorModel& model,
                      std::uint64_t seed) {
  CheckOption(level > 0.0 && level <= 1.0, "low-light level must be in (0, 1]");
  if (level == 1.0) return image.clone();
  cv::RNG rng(seed);
  return SimulatorForLevel(image, level, model).Apply(image, rng);
}

FrameTransform SequenceDarkener(const cv::Mat& reference, double level, const SensorModel& model,
                                std::uint64_t seed) {
  CheckOption(level > 0.0 && level <= 1.0, "low-light level must be in (0, 1]");
  if (level == 1.0) return {};
  auto simulator =
      std::make_shared<const LowLightSimulator>(SimulatorForLevel(reference, level, model));
  return [simulator, seed](int index, const cv::Mat& image) {
    cv::RNG rng(seed + static_cast<std::uint64_t>(index));
    return simulator->Apply(image, rng);
  };
}

}  // namespace noctua::sim
