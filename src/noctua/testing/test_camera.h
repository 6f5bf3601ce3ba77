#pragma once

#include "noctua/geometry/camera.h"

namespace noctua::testing {

// The camera of generated test scenes: 640 x 480, focal length 500 px, principal point at the
// centre, no distortion, so a point (x, y, z) projects to (500 x / z + 320, 500 y / z + 240).
inline geometry::PinholeCamera TestCamera() {
  geometry::Intrinsics intrinsics;
  intrinsics.fx = intrinsics.fy = 500.0;
  intrinsics.cx = 320.0;
  intrinsics.cy = 240.0;
  intrinsics.width = 640;
  intrinsics.height = 480;
  return geometry::PinholeCamera(intrinsics, geometry::Distortion{});
}

}  // namespace noctua::testing
