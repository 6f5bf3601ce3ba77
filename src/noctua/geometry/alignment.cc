#include "noctua/geometry/alignment.h"

#include <Eigen/Geometry>
#include <string>

#include "noctua/util/error.h"

// GCC 12 at -O3 reports a false "may be used uninitialized" inside Eigen::umeyama's inlined SVD.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace noctua::geometry {

Similarity AlignUmeyama(const std::vector<Eigen::Vector3d>& source,
                        const std::vector<Eigen::Vector3d>& target, bool with_scale) {
  if (source.size() != target.size()) {
    throw Error("alignment needs point sets of equal size, got " + std::to_string(source.size()) +
                " and " + std::to_string(target.size()));
  }
  if (source.size() < 3) {
    throw Error("alignment needs at least 3 point pairs, got " + std::to_string(source.size()));
  }
  const auto count = static_cast<Eigen::Index>(source.size());
  Eigen::Matrix3Xd src(3, count);
  Eigen::Matrix3Xd dst(3, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    src.col(i) = source[static_cast<std::size_t>(i)];
    dst.col(i) = target[static_cast<std::size_t>(i)];
  }
  const Eigen::Vector3d mean = src.rowwise().mean();
  const double spread = (src.colwise() - mean).squaredNorm() / static_cast<double>(count);
  if (spread < 1e-18) throw Error("alignment is undetermined: the source points all coincide");

  const Eigen::Matrix4d transform = Eigen::umeyama(src, dst, with_scale);
  const Eigen::Matrix3d scaled_rotation = transform.topLeftCorner<3, 3>();
  const double scale = with_scale ? std::cbrt(scaled_rotation.determinant()) : 1.0;
  return {scaled_rotation / scale, transform.topRightCorner<3, 1>(), scale};
}

}  // namespace noctua::geometry
