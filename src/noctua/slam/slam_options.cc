#include "noctua/slam/slam_options.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <set>
#include <string>

#include "noctua/io/yaml_file.h"
#include "noctua/util/error.h"

namespace noctua::slam {

void TriangulationOptions::Check() const {
  CheckOption(covisibles >= 1, "slam: triangulation covisibles must be at least 1");
  CheckOption(min_baseline_ratio >= 0.0, "slam: triangulation min_baseline_ratio must be >= 0");
  CheckOption(max_parallax_cos > 0.0 && max_parallax_cos < 1.0,
              "slam: triangulation max_parallax_cos must be in (0, 1)");
  CheckOption(match_ratio > 0.0 && match_ratio <= 1.0,
              "slam: triangulation match_ratio must be in (0, 1]");
  CheckOption(scale_consistency >= 1.0, "slam: triangulation scale_consistency must be >= 1");
}

void LoopClosingOptions::Check() const {
  CheckOption(consistency >= 1, "slam: loop consistency must be at least 1");
  CheckOption(min_keyframes >= 1, "slam: loop min_keyframes must be at least 1");
  CheckOption(min_feature_matches >= 3, "slam: loop min_feature_matches must be at least 3");
  CheckOption(ransac_iterations >= 1, "slam: loop ransac_iterations must be at least 1");
  CheckOption(min_ransac_inliers >= 3, "slam: loop min_ransac_inliers must be at least 3");
  CheckOption(min_loop_inliers >= min_ransac_inliers,
              "slam: loop min_loop_inliers must be at least min_ransac_inliers");
  CheckOption(essential_min_weight >= 1, "slam: loop essential_min_weight must be at least 1");
  CheckOption(pose_graph_iterations >= 1, "slam: loop pose_graph_iterations must be at least 1");
  CheckOption(global_ba_iterations >= 0, "slam: loop global_ba_iterations must not be negative");
}

void SlamOptions::Check() const {
  CheckOption(scale_factor > 1.0, "slam: scale_factor must be greater than 1");
  CheckOption(num_levels >= 1 && num_levels <= 32, "slam: num_levels must be in [1, 32]");
  CheckOption(bf > 0.0, "slam: bf (baseline times fx) must be positive");
  CheckOption(close_depth_m > 0.0, "slam: close_depth_m must be positive");
  CheckOption(min_depth_m >= 0.0, "slam: min_depth_m must not be negative");
  CheckOption(rolling_shutter_s >= 0.0 && rolling_shutter_s < 1.0,
              "Camera.rolling_shutter_s must be in [0, 1) seconds");
  CheckOption(max_depth_m == 0.0 || max_depth_m > min_depth_m,
              "slam: max_depth_m must be 0 (no limit) or greater than min_depth_m");
  CheckOption(min_initial_points >= 10, "slam: min_initial_points must be at least 10");
  CheckOption(min_tracked_inliers >= 10, "slam: min_tracked_inliers must be at least 10");
  CheckOption(min_certain_inliers >= 6 && min_certain_inliers <= min_tracked_inliers,
              "slam: min_certain_inliers must be in [6, min_tracked_inliers]");
  CheckOption(final_ba_iterations >= 0, "slam: final_ba_iterations must not be negative");
  CheckOption(refine_frames_after_keyframes >= 0,
              "slam: refine_frames_after_keyframes must not be negative");
  CheckOption(certain_sigma_ratio >= 0.0, "slam: certain_sigma_ratio must not be negative");
  CheckOption(motion_prior_acceleration_mps2 >= 0.0,
              "slam: motion_prior_acceleration_mps2 must not be negative");
  CheckOption(motion_prior_outlier_sigmas >= 0.0,
              "slam: motion_prior_outlier_sigmas must not be negative");
  CheckOption(max_coasting_frames >= 0, "slam: max_coasting_frames must not be negative");
  CheckOption(min_inliers_after_relocalisation >= min_tracked_inliers,
              "slam: min_inliers_after_relocalisation must be at least min_tracked_inliers");
  CheckOption(max_frames_between_keyframes >= 1, "slam: max_frames_between_keyframes must be >= 1");
  CheckOption(keyframe_pause_after_relocalisation >= 0,
              "slam: keyframe_pause_after_relocalisation must not be negative");
  CheckOption(relocalisation_candidates >= 1, "slam: relocalisation_candidates must be >= 1");
  CheckOption(localisation_keyframes >= 0, "slam: localisation_keyframes must not be negative");
  temporal_denoise.Check();
  CheckOption(local_ba_iterations >= 1, "slam: local_ba_iterations must be >= 1");
  CheckOption(local_ba_max_covisibles >= 0, "slam: local_ba_max_covisibles must be >= 0");
  CheckOption(mapping_slice_ms >= 0.0, "slam: mapping_slice_ms must not be negative");
  CheckOption(max_queued_keyframes >= 1, "slam: max_queued_keyframes must be >= 1");
  CheckOption(keyframe_redundancy > 0.0 && keyframe_redundancy <= 1.0,
              "slam: keyframe_redundancy must be in (0, 1]");
  triangulation.Check();
  loop_closing.Check();
  moving.Check();
  CheckOption(moving_frames_to_cull >= 1, "slam: moving_frames_to_cull must be at least 1");
}

std::shared_ptr<const place::Vocabulary> LoadSlamVocabulary(const SlamOptions& options) {
  if (options.vocabulary.empty() || options.vocabulary == "none") return nullptr;
  if (options.vocabulary != "default") return place::LoadVocabularyShared(options.vocabulary);
  const std::filesystem::path path = place::FindDefaultVocabulary();
  if (path.empty()) {
    static std::atomic<bool> warned{false};
    if (!warned.exchange(true)) {
      spdlog::warn(
          "slam: the default vocabulary (share/noctua/vocabulary/default.vocab) was not found; "
          "relocalisation matches against every keyframe (set NOCTUA_VOCABULARY)");
    }
    return nullptr;
  }
  return place::LoadVocabularyShared(path);
}

namespace {

// noctua's own `slam:` settings (ORB-SLAM's files have none of these).
void ReadSlamSection(const YAML::Node& root, const std::string& source, SlamOptions& options) {
  const YAML::Node section = root["slam"];
  if (!section.IsDefined() || section.IsNull()) return;
  if (!section.IsMap()) {
    ThrowLineError(source, section.Mark().line + 1, "'slam' must be a map of settings");
  }
  static const std::set<std::string> kKnown = {"triangulate",
                                               "triangulation_covisibles",
                                               "max_depth_m",
                                               "max_coasting_frames",
                                               "min_initial_points",
                                               "min_tracked_inliers",
                                               "min_inliers_after_relocalisation",
                                               "certain_sigma_ratio",
                                               "bridge_coasted_frames",
                                               "depth_fallback",
                                               "motion_prior_acceleration_mps2",
                                               "motion_prior_outlier_sigmas",
                                               "loop_closing",
                                               "loop_min_inliers",
                                               "probation_for_new_points",
                                               "final_ba_iterations",
                                               "refine_frames_after_keyframes",
                                               "localisation_keyframes",
                                               "smooth_trajectory",
                                               "temporal_denoise"};
  for (const auto& entry : section) {
    const auto key = entry.first.as<std::string>();
    if (!kKnown.contains(key)) {
      ThrowLineError(source, entry.first.Mark().line + 1, "unknown setting 'slam." + key + "'");
    }
  }
  io::ReadSetting(section, "triangulate", source, options.triangulation.enabled);
  io::ReadSetting(section, "triangulation_covisibles", source, options.triangulation.covisibles);
  io::ReadSetting(section, "max_depth_m", source, options.max_depth_m);
  io::ReadSetting(section, "max_coasting_frames", source, options.max_coasting_frames);
  io::ReadSetting(section, "min_initial_points", source, options.min_initial_points);
  io::ReadSetting(section, "min_tracked_inliers", source, options.min_tracked_inliers);
  io::ReadSetting(section, "min_inliers_after_relocalisation", source,
                  options.min_inliers_after_relocalisation);
  io::ReadSetting(section, "certain_sigma_ratio", source, options.certain_sigma_ratio);
  io::ReadSetting(section, "bridge_coasted_frames", source, options.bridge_coasted_frames);
  io::ReadSetting(section, "depth_fallback", source, options.depth_fallback);
  io::ReadSetting(section, "motion_prior_acceleration_mps2", source,
                  options.motion_prior_acceleration_mps2);
  io::ReadSetting(section, "motion_prior_outlier_sigmas", source,
                  options.motion_prior_outlier_sigmas);
  io::ReadSetting(section, "loop_closing", source, options.loop_closing.enabled);
  io::ReadSetting(section, "loop_min_inliers", source, options.loop_closing.min_loop_inliers);
  io::ReadSetting(section, "probation_for_new_points", source, options.probation_for_new_points);
  io::ReadSetting(section, "final_ba_iterations", source, options.final_ba_iterations);
  io::ReadSetting(section, "refine_frames_after_keyframes", source,
                  options.refine_frames_after_keyframes);
  io::ReadSetting(section, "localisation_keyframes", source, options.localisation_keyframes);
  io::ReadSetting(section, "smooth_trajectory", source, options.smooth_trajectory);
  io::ReadSetting(section, "temporal_denoise", source, options.temporal_denoise.enabled);
}

}  // namespace

SlamSetup LoadSlamSetup(const std::filesystem::path& path) {
  SlamSetup setup;
  setup.camera = io::ReadCameraConfig(path);
  const YAML::Node root = io::LoadYamlFile(path);
  const double fx = setup.camera.intrinsics.fx;
  SlamOptions& options = setup.options;
  options.scale_factor = setup.camera.orb.scale_factor;
  options.num_levels = setup.camera.orb.num_levels;
  options.bf = io::OptionalNumber(root, "Camera.bf", fx * 0.0773, path);
  options.close_depth_m = io::OptionalNumber(root, "ThDepth", 40.0, path) * options.bf / fx;
  options.rolling_shutter_s = io::OptionalNumber(root, "Camera.rolling_shutter_s", 0.0, path);
  if (const YAML::Node vocabulary = root["Vocabulary.file"]; vocabulary) {
    if (!vocabulary.IsScalar()) ThrowFileError(path, "Vocabulary.file must be a file name");
    options.vocabulary = vocabulary.as<std::string>();
    const bool named =
        options.vocabulary != "" && options.vocabulary != "none" && options.vocabulary != "default";
    if (named && std::filesystem::path(options.vocabulary).is_relative()) {
      options.vocabulary = (path.parent_path() / options.vocabulary).string();
    }
  }
  ReadSlamSection(root, path.string(), options);
  try {
    options.Check();
  } catch (const Error& error) {
    ThrowFileError(path, error.what());
  }
  return setup;
}

}  // namespace noctua::slam
