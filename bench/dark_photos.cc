// Not a timing benchmark: how every method matches on real dark photos (LOL's 20 and DICM's 10;
// no simulation), the check of the low-light methods on light that no sensor model of ours made.
// Protocol: eval::MatchWarpedPair (a photo against a copy warped by a known similarity, both
// with fresh noise of the photo's own level, ratio test 0.8, correct within 3 px).
// Prints a Markdown table: per method and photo set, mean keypoints, correct matches, the share
// of matches that are correct, and the repeatability (the photo's points the copy detected again
// within 3 px, whatever the descriptors say). Usage: dark_photos
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "noctua/eval/warped_pair.h"
#include "noctua/pipeline/method.h"
#include "noctua/testing/shared_data.h"

namespace {

namespace fs = std::filesystem;

struct PhotoSet {
  std::string name;
  std::vector<cv::Mat> photos;
};

PhotoSet LoadPhotos(const std::string& name, const fs::path& dir) {
  std::vector<fs::path> paths;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string extension = entry.path().extension().string();
    if (extension == ".png" || extension == ".jpg") paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  PhotoSet set{name, {}};
  for (const auto& path : paths) {
    set.photos.push_back(noctua::testing::ReadImageOrThrow(path, cv::IMREAD_COLOR));
  }
  return set;
}

}  // namespace

int main() {
  const fs::path lowlight = noctua::testing::DataDir() / "lowlight";
  const std::vector<PhotoSet> sets = {LoadPhotos("LOL (20)", lowlight / "lol_low20" / "low"),
                                      LoadPhotos("DICM (10)", lowlight / "dicm10")};
  std::cout << "| method | photos | keypoints | matches | correct | correct share | "
               "repeatability |\n|---|---|---:|---:|---:|---:|---:|\n";
  for (const std::string name : {"orb-opencv", "orb", "he-orb", "clahe-orb", "paper", "noctua"}) {
    auto method = noctua::pipeline::CreateMethod(name, noctua::pipeline::MethodConfig());
    for (const PhotoSet& set : sets) {
      noctua::eval::WarpedPairResult sum;
      unsigned seed = 1;
      for (const cv::Mat& photo : set.photos) {
        const auto pair =
            noctua::eval::MatchWarpedPair(*method, photo, noctua::eval::WarpedPairOptions(), seed);
        seed += 2;
        sum.keypoints += pair.keypoints;
        sum.matches += pair.matches;
        sum.correct += pair.correct;
        sum.comparable += pair.comparable;
        sum.repeated += pair.repeated;
      }
      const double n = static_cast<double>(set.photos.size());
      std::cout << "| " << name << " | " << set.name << " | "
                << cv::format(
                       "%.0f | %.0f | %.0f | %.2f | %.2f", sum.keypoints / n, sum.matches / n,
                       sum.correct / n,
                       sum.matches > 0 ? static_cast<double>(sum.correct) / sum.matches : 0.0,
                       sum.comparable > 0 ? static_cast<double>(sum.repeated) / sum.comparable
                                          : 0.0)
                << " |" << std::endl;
    }
  }
  return 0;
}
