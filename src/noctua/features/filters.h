#pragma once

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

namespace noctua::features {

// The paper's three filters. Points are in the pixel coordinates of their pyramid level
// (`octave`); `scale` converts a level's coordinates to level 0, where masks and edge maps live.

// Position of a level point in level-0 pixels, clamped into a map of `size`.
cv::Point ToLevelZeroPixel(const cv::KeyPoint& point, double scale, const cv::Size& size);

// Removes points whose level-0 pixel in `mask` (CV_8U, level-0 size) is non-zero when
// `drop_where_set`, or zero otherwise (OpenCV's Feature2D mask convention). Returns how many
// points remain.
void FilterByMask(std::vector<cv::KeyPoint>& points, double scale, const cv::Mat& mask,
                  bool drop_where_set);

// Keeps points with an edge pixel (non-zero in the CV_8U level-0 `edge_map`) within `radius_px`
// pixels of their own level, that is radius_px * scale level-0 pixels (Euclidean), of their
// level-0 pixel. Looks only at that disc around each point: no per-frame map is needed. The
// points removed are appended to `dropped` when it is given.
void FilterByEdgeDistance(std::vector<cv::KeyPoint>& points, double scale, const cv::Mat& edge_map,
                          double radius_px, std::vector<cv::KeyPoint>* dropped = nullptr);

// The candidates for topping up a level the filters left short (EdgeFilterOptions::fill_to_quota):
// the points the edge filter `dropped`, without those whose window x window neighbourhood holds a
// point already `kept`, then thinned by the same non-maximum suppression (so no two points end up
// closer than the suppression allows). All points belong to one level of size `level_size`.
std::vector<cv::KeyPoint> FillCandidates(std::vector<cv::KeyPoint> dropped,
                                         const std::vector<cv::KeyPoint>& kept,
                                         const cv::Size& level_size, int window);

// Keeps, within every window x window neighbourhood of one level, only the point with the highest
// response (ties: the first one seen). Points must all belong to one level of size `level_size`.
void SuppressNonMaxima(std::vector<cv::KeyPoint>& points, const cv::Size& level_size, int window);

}  // namespace noctua::features
