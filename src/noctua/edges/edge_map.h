#pragma once

#include <opencv2/core.hpp>

#include "noctua/edges/phase_congruency.h"

namespace noctua::edges {

// Thinning and hysteresis that turn a PC strength map into a binary edge map.
struct EdgeMapOptions {
  // Hysteresis on PC (in [0, 1]): pixels >= high start an edge, which grows over 8-connected
  // thinned pixels >= low. Defaults near Kovesi's suggested 0.1 / 0.2.
  double low_threshold = 0.1;
  double high_threshold = 0.2;

  void Check() const;
};

// Keeps a pixel's strength where it is a maximum along the feature normal (`orientation`,
// radians anticlockwise from +x with y up, as PhaseCongruency::orientation), comparing with
// the bilinearly interpolated strengths one pixel away on both sides (orientation rounded to
// whole degrees); 0 elsewhere, on the one-pixel border and below `min_strength`. Ties go to the
// pixel on the far side along the normal, so a symmetric two-pixel ridge keeps exactly one pixel.
// Both inputs CV_32F of one size; throws noctua::Error otherwise.
cv::Mat NonMaximumSuppression(const cv::Mat& strength, const cv::Mat& orientation,
                              double min_strength = 0.0);

// CV_8U map, 255 on pixels of 8-connected components of (strength >= low, > 0) that hold at
// least one pixel >= high, 0 elsewhere. Throws noctua::Error for non-CV_32F input or low > high.
cv::Mat HysteresisThreshold(const cv::Mat& strength, double low, double high);

// NMS of the maximum moment along the orientation, then hysteresis: the CV_8U edge map that
// the extractor's edge filter takes.
cv::Mat EdgeMapFromPhaseCongruency(const PhaseCongruency& pc, const EdgeMapOptions& options);

// Draws an edge map made on an image reduced `factor` times (INTER_AREA, so that reduced pixel c
// covers full pixels [c * factor, (c + 1) * factor)) into a CV_8U map of `full_size`, keeping
// lines one pixel wide: each edge pixel goes to its sub-pixel position along the normal (the
// vertex of a parabola through the strengths at the pixel and one reduced pixel to either side,
// at most half a reduced pixel away), and 8-neighbouring edge pixels are joined by 8-connected
// lines. `pc` is what `edges` was made from. Throws noctua::Error when the sizes do not fit.
cv::Mat EnlargeEdgeMap(const cv::Mat& edges, const PhaseCongruency& pc, cv::Size full_size,
                       int factor);

}  // namespace noctua::edges

namespace noctua::edges {

// Agreement of two binary edge maps with a localisation tolerance: an edge pixel of `test` is
// correct when an edge pixel of `reference` lies within `tolerance_px` (in x and y), and an
// edge pixel of `reference` is found when one of `test` lies that near.
struct EdgeAgreement {
  double precision = 0.0;
  double recall = 0.0;
  double f_measure = 0.0;  // 2PR / (P + R); 1 when both maps are empty, 0 when one is
  int test_pixels = 0;
  int reference_pixels = 0;
};

// Both CV_8U of one size (non-zero = edge); throws noctua::Error otherwise.
EdgeAgreement CompareEdgeMaps(const cv::Mat& test, const cv::Mat& reference, int tolerance_px = 1);

}  // namespace noctua::edges
