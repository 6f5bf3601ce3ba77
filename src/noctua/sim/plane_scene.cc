#include "noctua/sim/plane_scene.h"

#include <Eigen/Geometry>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "noctua/io/image_file.h"
#include "noctua/io/output_dir.h"
#include "noctua/util/error.h"

namespace noctua::sim {

namespace fs = std::filesystem;

void PlaneSceneOptions::Check() const {
  CheckOption(num_frames >= 2, "plane scene needs at least 2 frames");
  CheckOption(wall_distance_m > 0.5, "plane scene wall_distance_m must exceed 0.5 m");
  CheckOption(wall_width_m > 0.0, "plane scene wall_width_m must be positive");
  CheckOption(fps > 0.0, "plane scene fps must be positive");
}

void WritePlaneScene(const cv::Mat& texture, const PlaneSceneOptions& options,
                     const fs::path& dir) {
  options.Check();
  if (texture.empty() || texture.type() != CV_8UC3) {
    throw Error("plane scene: the texture must be an 8-bit BGR image");
  }
  if (!fs::is_directory(dir)) ThrowFileError(dir, "output folder does not exist");
  constexpr int kWidth = 640, kHeight = 480;
  constexpr double kF = 525.0, kCx = 319.5, kCy = 239.5;
  constexpr double kDepthFactor = 5000.0;
  const double metres_to_texels = texture.cols / options.wall_width_m;
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ostringstream rgb, depth, associations, ground_truth;
  rgb << "# color images\n# timestamp filename\n";
  depth << "# depth maps\n# timestamp filename\n";
  ground_truth << "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  ground_truth << std::fixed << std::setprecision(6);
  for (int k = 0; k < options.num_frames; ++k) {
    // Camera k: panned about the vertical axis and moved sideways, centred on the pan.
    const double centred = k - (options.num_frames - 1) / 2.0;
    const double yaw = centred * options.yaw_per_frame_deg * std::numbers::pi / 180.0;
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).matrix();
    const Eigen::Vector3d position(centred * options.shift_per_frame_m, 0.0, 0.0);
    cv::Mat map_x(kHeight, kWidth, CV_32FC1), map_y(kHeight, kWidth, CV_32FC1);
    cv::Mat depth16(kHeight, kWidth, CV_16UC1);
    for (int v = 0; v < kHeight; ++v) {
      for (int u = 0; u < kWidth; ++u) {
        const Eigen::Vector3d ray = rotation * Eigen::Vector3d((u - kCx) / kF, (v - kCy) / kF, 1);
        // The pixel's ray meets the wall z = d at lambda; its depth (camera z) is lambda, since
        // the camera-frame ray has z = 1.
        const double lambda = (options.wall_distance_m - position.z()) / ray.z();
        const Eigen::Vector3d point = position + lambda * ray;
        map_x.at<float>(v, u) =
            static_cast<float>(texture.cols / 2.0 + point.x() * metres_to_texels);
        map_y.at<float>(v, u) =
            static_cast<float>(texture.rows / 2.0 + point.y() * metres_to_texels);
        depth16.at<std::uint16_t>(v, u) = cv::saturate_cast<std::uint16_t>(lambda * kDepthFactor);
      }
    }
    cv::Mat image;
    cv::remap(texture, image, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
    const double t = 1000.0 + k / options.fps;
    std::ostringstream stamp;
    stamp << std::fixed << std::setprecision(6) << t;
    io::WriteImage(dir / "rgb" / (stamp.str() + ".png"), image);
    io::WriteImage(dir / "depth" / (stamp.str() + ".png"), depth16);
    rgb << stamp.str() << " rgb/" << stamp.str() << ".png\n";
    depth << stamp.str() << " depth/" << stamp.str() << ".png\n";
    associations << stamp.str() << " rgb/" << stamp.str() << ".png " << stamp.str() << " depth/"
                 << stamp.str() << ".png\n";
    const Eigen::Quaterniond q(rotation);
    ground_truth << t << ' ' << position.x() << ' ' << position.y() << ' ' << position.z() << ' '
                 << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << "\n";
  }
  io::WriteTextFileAtomically(dir / "rgb.txt", rgb.str());
  io::WriteTextFileAtomically(dir / "depth.txt", depth.str());
  io::WriteTextFileAtomically(dir / "associations.txt", associations.str());
  io::WriteTextFileAtomically(dir / "groundtruth.txt", ground_truth.str());
  io::WriteTextFileAtomically(
      dir / "camera.yaml",
      "%YAML:1.0\n# The generated plane scene's ideal pinhole camera.\n"
      "Camera.fx: 525.0\nCamera.fy: 525.0\nCamera.cx: 319.5\nCamera.cy: 239.5\n"
      "Camera.width: 640\nCamera.height: 480\nDepthMapFactor: 5000.0\n");
}

}  // namespace noctua::sim
