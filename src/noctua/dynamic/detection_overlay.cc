#include "noctua/dynamic/detection_overlay.h"

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "noctua/dynamic/coco.h"
#include "noctua/util/error.h"

namespace noctua::dynamic {
namespace {

cv::Scalar LevelColour(MotionLevel level) {
  switch (level) {
    case MotionLevel::kHigh:
      return {40, 40, 230};
    case MotionLevel::kMedium:
      return {0, 165, 255};
    case MotionLevel::kLow:
      return {0, 215, 215};
    case MotionLevel::kStatic:
      break;
  }
  return {200, 160, 60};
}

}  // namespace

cv::Mat DrawDetections(const cv::Mat& image, const std::vector<Detection>& detections,
                       const cv::Mat& dynamic_mask, const MotionLevelTable& table,
                       const DynamicMaskOptions& mask_options) {
  cv::Mat bgr;
  if (image.channels() == 1) {
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  } else {
    bgr = image.clone();
  }
  cv::Mat tinted = bgr.clone();
  tinted.setTo(cv::Scalar(40, 40, 230), dynamic_mask);
  cv::addWeighted(bgr, 0.6, tinted, 0.4, 0.0, bgr);
  const double font = std::max(0.4, bgr.cols / 1600.0);
  const int thin = std::max(1, bgr.cols / 640);
  for (const auto& d : detections) {
    const MotionLevel level = table.Level(d.class_id);
    const bool is_dynamic = mask_options.dynamic_levels.count(level) > 0;
    const cv::Scalar colour = LevelColour(level);
    if (!d.mask.empty()) {
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(d.mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
      cv::drawContours(bgr, contours, -1, colour, thin, cv::LINE_AA);
    }
    cv::rectangle(bgr, d.box, colour, is_dynamic ? 2 * thin : thin, cv::LINE_AA);
    char label[96];
    std::snprintf(label, sizeof(label), "%s %.2f %s", CocoClassName(d.class_id).c_str(), d.score,
                  ToString(level).c_str());
    int baseline = 0;
    const cv::Size text = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, thin, &baseline);
    const cv::Point origin(cvRound(d.box.x), std::max(text.height + 4, cvRound(d.box.y)));
    cv::rectangle(
        bgr,
        cv::Rect(origin.x, origin.y - text.height - 4, text.width + 4, text.height + 4 + baseline),
        colour, cv::FILLED);
    cv::putText(bgr, label, {origin.x + 2, origin.y - 2}, cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(255, 255, 255), thin, cv::LINE_AA);
  }
  return bgr;
}

nlohmann::json DetectionsJson(const std::vector<Detection>& detections,
                              const MotionLevelTable& table,
                              const DynamicMaskOptions& mask_options) {
  nlohmann::json found = nlohmann::json::array();
  for (const auto& d : detections) {
    const auto level = table.Level(d.class_id);
    nlohmann::json entry = {{"class", CocoClassName(d.class_id)},
                            {"class_id", d.class_id},
                            {"score", d.score},
                            {"box", {d.box.x, d.box.y, d.box.br().x, d.box.br().y}},
                            {"motion_level", ToString(level)},
                            {"dynamic", mask_options.dynamic_levels.count(level) > 0}};
    if (!d.mask.empty()) entry["mask_area"] = cv::countNonZero(d.mask);
    found.push_back(entry);
  }
  return found;
}

cv::Size ParseInputSize(const std::string& text, const std::string& what) {
  int width = 0, height = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || x != 'x' || !in.eof()) {
    throw Error(what + " '" + text + "': expected WIDTHxHEIGHT, e.g. 320x256");
  }
  return {width, height};
}

}  // namespace noctua::dynamic
