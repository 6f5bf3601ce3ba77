#pragma once

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "noctua/features/extractor_options.h"
#include "noctua/features/pyramid.h"

namespace noctua::features {

// ORB-SLAM's geometry: no point closer than kEdgeThreshold to a level's border, so that the
// 31x31 descriptor patch, rotated, stays inside the (border-extended) level.
inline constexpr int kEdgeThreshold = 19;
inline constexpr int kPatchSize = 31;
inline constexpr int kHalfPatchSize = 15;

// The number of points ORB-SLAM wants from each level: a geometric share, so that every level
// gets points in proportion to its area's side length, the last level taking the remainder.
std::vector<int> FeaturesPerLevel(const PyramidFastOptions& options, int num_levels);

// FAST corners of one level (level pixel coordinates, octave = level, response = FAST score),
// with a grid fallback: the whole level at the initial threshold, then each grid cell that found
// nothing again at the minimum threshold, so that dark or flat regions still contribute points.
std::vector<cv::KeyPoint> DetectGridFast(const cv::Mat& level_image, int level,
                                         const PyramidFastOptions& options);

// Spreads points over `bounds` like ORB-SLAM's octree: the region is split into quadrants,
// always the quadrant with the most points first, until there are `target` regions; each region
// keeps its strongest point. Returns all points when there are no more than `target`.
std::vector<cv::KeyPoint> DistributeOverImage(const std::vector<cv::KeyPoint>& points,
                                              const cv::Rect2f& bounds, int target);

// Orientation by intensity centroid over a disc of radius kHalfPatchSize, in degrees [0, 360).
void ComputeOrientation(const cv::Mat& level_image, std::vector<cv::KeyPoint>& points);

}  // namespace noctua::features
