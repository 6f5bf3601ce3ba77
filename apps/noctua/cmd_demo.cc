// noctua demo: the extractor on a scene it draws itself, in normal and low light.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>

#include "commands.h"
#include "noctua/demo/demo.h"
#include "noctua/io/output_dir.h"

namespace noctua::app {
namespace {

struct DemoFlags {
  std::string out = "noctua-demo";
  bool force = false;
  unsigned seed = 7;
};

// Low light as a camera records it: linear light scaled down, shot and read noise, gamma, 8 bits.
// `grey_fraction` is the share of the original mean grey value that remains (SPEC: "15%").
cv::Mat Darken(const cv::Mat& image, double grey_fraction, unsigned seed) {
  constexpr double kGamma = 2.2;
  cv::Mat linear;
  image.convertTo(linear, CV_32F, 1.0 / 255.0);
  cv::pow(linear, kGamma, linear);
  linear *= std::pow(grey_fraction, kGamma);
  constexpr double kFullWellElectrons = 4000.0;
  constexpr double kReadNoiseElectrons = 4.0;
  cv::Mat electrons = linear * kFullWellElectrons;
  cv::Mat noise(electrons.size(), electrons.type());
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat shot_sigma;
  cv::sqrt(cv::max(electrons, 0.0), shot_sigma);
  electrons += noise.mul(shot_sigma);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, kReadNoiseElectrons);
  electrons += noise;
  cv::Mat out = cv::max(electrons / kFullWellElectrons, 0.0);
  cv::pow(out, 1.0 / kGamma, out);
  out.convertTo(out, CV_8U, 255.0);
  return out;
}

bool IsEarlierDemoFolder(const std::filesystem::path& dir) {
  return std::filesystem::exists(dir / ".noctua-demo");
}

void RunDemo(const DemoFlags& flags) {
  const std::filesystem::path out_dir = flags.out;
  io::PrepareOutputDir(out_dir, flags.force || IsEarlierDemoFolder(out_dir));
  io::WriteTextFileAtomically(out_dir / ".noctua-demo",
                              "outputs of noctua demo; safe to overwrite\n");
  demo::DemoOptions options;
  options.seed = flags.seed;
  options.darken = Darken;
  demo::RunDemo(options, out_dir, std::cout);
  std::cout << "wrote scenes, overlays, sequences, evaluation reports, summary.md and "
               "summary.json to "
            << std::filesystem::absolute(out_dir).string() << "\n";
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto flags = std::make_shared<DemoFlags>();
  CLI::App* command =
      app.add_subcommand("demo", "Show what noctua does on a scene it generates (no data needed)");
  command->add_option("-o,--out", flags->out, "Output folder")->capture_default_str();
  command->add_option("--seed", flags->seed, "Seed of the generated scene")->capture_default_str();
  command->add_flag("--force", flags->force, "Write into an existing, non-empty output folder");
  command->callback([flags] { RunDemo(*flags); });
}

}  // namespace noctua::app
