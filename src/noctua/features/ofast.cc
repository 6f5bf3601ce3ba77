#include "noctua/features/ofast.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <utility>

namespace noctua::features {

std::vector<int> FeaturesPerLevel(const PyramidFastOptions& options, int num_levels) {
  std::vector<int> wanted(static_cast<std::size_t>(num_levels), 0);
  const double factor = 1.0 / options.scale_factor;
  double per_level = options.num_features * (1.0 - factor) /
                     (1.0 - std::pow(factor, static_cast<double>(num_levels)));
  int assigned = 0;
  for (int l = 0; l + 1 < num_levels; ++l) {
    wanted[static_cast<std::size_t>(l)] = static_cast<int>(std::lround(per_level));
    assigned += wanted[static_cast<std::size_t>(l)];
    per_level *= factor;
  }
  wanted.back() = std::max(options.num_features - assigned, 0);
  return wanted;
}

std::vector<cv::KeyPoint> DetectGridFast(const cv::Mat& level_image, int level,
                                         const PyramidFastOptions& options) {
  // FAST keeps 3 pixels of its input as border; the search area is widened by that much so that
  // corners land exactly in [kEdgeThreshold, size - kEdgeThreshold).
  constexpr int kFastBorder = 3;
  const cv::Rect search(kEdgeThreshold - kFastBorder, kEdgeThreshold - kFastBorder,
                        level_image.cols - 2 * (kEdgeThreshold - kFastBorder),
                        level_image.rows - 2 * (kEdgeThreshold - kFastBorder));
  std::vector<cv::KeyPoint> corners;
  if (search.width <= 2 * kFastBorder || search.height <= 2 * kFastBorder) return corners;

  cv::FAST(level_image(search), corners, options.initial_fast_threshold, true);
  for (auto& corner : corners) corner.pt += cv::Point2f(search.tl());

  // Cells over the area where corners can lie.
  const cv::Rect inner(kEdgeThreshold, kEdgeThreshold, search.width - 2 * kFastBorder,
                       search.height - 2 * kFastBorder);
  const int cells_x = std::max(1, inner.width / options.cell_size);
  const int cells_y = std::max(1, inner.height / options.cell_size);
  const float cell_w = static_cast<float>(inner.width) / static_cast<float>(cells_x);
  const float cell_h = static_cast<float>(inner.height) / static_cast<float>(cells_y);
  auto cell_of = [&](const cv::Point2f& pt) {
    const int cx = std::min(cells_x - 1, static_cast<int>((pt.x - inner.x) / cell_w));
    const int cy = std::min(cells_y - 1, static_cast<int>((pt.y - inner.y) / cell_h));
    return cy * cells_x + cx;
  };
  std::vector<int> count(static_cast<std::size_t>(cells_x * cells_y), 0);
  for (const auto& corner : corners) ++count[static_cast<std::size_t>(cell_of(corner.pt))];

  // Fallback for empty cells. Every cv::FAST call costs a fixed overhead, so consecutive empty
  // cells of a row share one call; when most cells are empty, one pass over the level is cheaper.
  // FAST scores do not depend on the threshold they were found at, so either way a cell gets
  // exactly the corners it would get from its own call.
  auto cell_rect = [&](int cx, int cy) {
    const int x0 = inner.x + static_cast<int>(std::floor(static_cast<float>(cx) * cell_w));
    const int y0 = inner.y + static_cast<int>(std::floor(static_cast<float>(cy) * cell_h));
    const int x1 = inner.x + static_cast<int>(std::floor(static_cast<float>(cx + 1) * cell_w));
    const int y1 = inner.y + static_cast<int>(std::floor(static_cast<float>(cy + 1) * cell_h));
    return cv::Rect(x0, y0, x1 - x0, y1 - y0);
  };
  const auto empty_cells = std::count(count.begin(), count.end(), 0);
  if (empty_cells == 0) {
    // nothing to add
  } else if (2 * empty_cells > static_cast<long>(count.size())) {
    std::vector<cv::KeyPoint> weak;
    cv::FAST(level_image(search), weak, options.min_fast_threshold, true);
    for (auto& corner : weak) {
      corner.pt += cv::Point2f(search.tl());
      if (count[static_cast<std::size_t>(cell_of(corner.pt))] == 0) corners.push_back(corner);
    }
  } else {
    std::vector<cv::KeyPoint> weak;
    for (int cy = 0; cy < cells_y; ++cy) {
      for (int cx = 0; cx < cells_x; ++cx) {
        if (count[static_cast<std::size_t>(cy * cells_x + cx)] > 0) continue;
        int run_end = cx;
        while (run_end + 1 < cells_x &&
               count[static_cast<std::size_t>(cy * cells_x + run_end + 1)] == 0) {
          ++run_end;
        }
        const cv::Rect run = cell_rect(cx, cy) | cell_rect(run_end, cy);
        const cv::Rect run_search =
            cv::Rect(run.x - kFastBorder, run.y - kFastBorder, run.width + 2 * kFastBorder,
                     run.height + 2 * kFastBorder) &
            search;
        cv::FAST(level_image(run_search), weak, options.min_fast_threshold, true);
        for (auto& corner : weak) {
          corner.pt += cv::Point2f(run_search.tl());
          // The widened search overlaps the neighbouring cells: keep only this run's corners.
          if (run.contains(cv::Point(cvFloor(corner.pt.x), cvFloor(corner.pt.y)))) {
            corners.push_back(corner);
          }
        }
        cx = run_end;
      }
    }
  }
  for (auto& corner : corners) {
    corner.octave = level;
    corner.size = static_cast<float>(kPatchSize);
  }
  return corners;
}

namespace {

struct Region {
  cv::Rect2f bounds;
  std::vector<int> members;
};

}  // namespace

std::vector<cv::KeyPoint> DistributeOverImage(const std::vector<cv::KeyPoint>& points,
                                              const cv::Rect2f& bounds, int target) {
  if (static_cast<int>(points.size()) <= target) return points;
  if (target <= 0) return {};

  // Start, as ORB-SLAM does, with roughly square regions side by side.
  const int initial = std::max(1, static_cast<int>(std::lround(bounds.width / bounds.height)));
  const float strip = bounds.width / static_cast<float>(initial);
  std::vector<Region> regions(static_cast<std::size_t>(initial));
  for (int i = 0; i < initial; ++i) {
    regions[static_cast<std::size_t>(i)].bounds =
        cv::Rect2f(bounds.x + strip * static_cast<float>(i), bounds.y, strip, bounds.height);
  }
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const float x = points[static_cast<std::size_t>(i)].pt.x;
    const int index = std::clamp(static_cast<int>((x - bounds.x) / strip), 0, initial - 1);
    regions[static_cast<std::size_t>(index)].members.push_back(i);
  }
  std::erase_if(regions, [](const Region& region) { return region.members.empty(); });

  // As ORB-SLAM's octree: each round splits every region holding more than one point, so sparse
  // parts of the image are refined as often as crowded ones; the round that would overshoot the
  // target splits the most crowded regions first and stops on reaching it.
  auto split = [&](Region parent, std::vector<Region>& into) {
    const float half_w = parent.bounds.width / 2.0f;
    const float half_h = parent.bounds.height / 2.0f;
    std::array<Region, 4> children;
    for (int c = 0; c < 4; ++c) {
      children[static_cast<std::size_t>(c)].bounds =
          cv::Rect2f(parent.bounds.x + half_w * static_cast<float>(c % 2),
                     parent.bounds.y + half_h * static_cast<float>(c / 2), half_w, half_h);
    }
    for (const int member : parent.members) {
      const cv::Point2f& pt = points[static_cast<std::size_t>(member)].pt;
      const int c =
          (pt.x >= parent.bounds.x + half_w ? 1 : 0) + (pt.y >= parent.bounds.y + half_h ? 2 : 0);
      children[static_cast<std::size_t>(c)].members.push_back(member);
    }
    for (auto& child : children) {
      if (!child.members.empty()) into.push_back(std::move(child));
    }
  };
  auto splittable = [](const Region& region) {
    return region.members.size() > 1 && region.bounds.width >= 1.0f && region.bounds.height >= 1.0f;
  };
  while (static_cast<int>(regions.size()) < target) {
    std::vector<Region> settled;
    std::vector<Region> to_split;
    for (auto& region : regions) {
      (splittable(region) ? to_split : settled).push_back(std::move(region));
    }
    if (to_split.empty()) {
      regions = std::move(settled);
      break;
    }
    const bool last_round = static_cast<int>(settled.size() + 4 * to_split.size()) >= target;
    if (last_round) {
      std::stable_sort(to_split.begin(), to_split.end(), [](const Region& a, const Region& b) {
        return a.members.size() > b.members.size();
      });
    }
    std::vector<Region> next = std::move(settled);
    for (std::size_t i = 0; i < to_split.size(); ++i) {
      const std::size_t unsplit_left = to_split.size() - i;
      if (last_round && static_cast<int>(next.size() + unsplit_left) >= target) {
        for (std::size_t j = i; j < to_split.size(); ++j) next.push_back(std::move(to_split[j]));
        break;
      }
      split(std::move(to_split[i]), next);
    }
    const bool stalled = next.size() == regions.size();
    regions = std::move(next);
    if (stalled) break;
  }
  const std::size_t live = regions.size();

  std::vector<cv::KeyPoint> kept;
  kept.reserve(live);
  for (const auto& region : regions) {
    if (region.members.empty()) continue;
    const int best =
        *std::max_element(region.members.begin(), region.members.end(), [&](int a, int b) {
          return points[static_cast<std::size_t>(a)].response <
                 points[static_cast<std::size_t>(b)].response;
        });
    kept.push_back(points[static_cast<std::size_t>(best)]);
  }
  // Splitting into four can overshoot the target by up to three; drop the weakest.
  if (static_cast<int>(kept.size()) > target) {
    std::nth_element(
        kept.begin(), kept.begin() + target, kept.end(),
        [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
    kept.resize(static_cast<std::size_t>(target));
  }
  return kept;
}

namespace {

// Half-widths of the disc u^2 + v^2 <= r^2 + r, row by row; the disc is symmetric under
// exchanging u and v, so the angle turns exactly with the image.
const std::array<int, kHalfPatchSize + 1>& DiscHalfWidths() {
  static const std::array<int, kHalfPatchSize + 1> half_widths = [] {
    std::array<int, kHalfPatchSize + 1> result{};
    const int limit = kHalfPatchSize * kHalfPatchSize + kHalfPatchSize;
    for (int v = 0; v <= kHalfPatchSize; ++v) {
      int u = 0;
      while ((u + 1) * (u + 1) + v * v <= limit) ++u;
      result[static_cast<std::size_t>(v)] = u;
    }
    return result;
  }();
  return half_widths;
}

// The moments (m10, m01) of the disc around `center`, pixel by pixel.
std::pair<int, int> DiscMoments(const uchar* center, int step) {
  const auto& half_widths = DiscHalfWidths();
  int m01 = 0;
  int m10 = 0;
  for (int u = -half_widths[0]; u <= half_widths[0]; ++u) m10 += u * center[u];
  for (int v = 1; v <= kHalfPatchSize; ++v) {
    int v_sum = 0;
    const int d = half_widths[static_cast<std::size_t>(v)];
    for (int u = -d; u <= d; ++u) {
      const int below = center[u + v * step];
      const int above = center[u - v * step];
      v_sum += below - above;
      m10 += u * (below + above);
    }
    m01 += v * v_sum;
  }
  return {m10, m01};
}

#if CV_SIMD128
// The same sums sixteen pixels at a time: each disc row is read as the 32 pixels
// u = -15..16 and weighted by u (for m10) or by 1 (for m01) inside the disc, 0 outside. Integer
// arithmetic throughout, so the moments are exactly those of DiscMoments.
constexpr int kRowSpan = 32;

struct DiscRowWeights {
  alignas(16) std::array<std::array<short, kRowSpan>, kHalfPatchSize + 1> arm;
  alignas(16) std::array<std::array<short, kRowSpan>, kHalfPatchSize + 1> inside;
};

const DiscRowWeights& RowWeights() {
  static const DiscRowWeights weights = [] {
    DiscRowWeights result{};
    const auto& half_widths = DiscHalfWidths();
    for (int v = 0; v <= kHalfPatchSize; ++v) {
      for (int i = 0; i < kRowSpan; ++i) {
        const int u = i - kHalfPatchSize;
        const bool in_disc = std::abs(u) <= half_widths[static_cast<std::size_t>(v)];
        result.arm[static_cast<std::size_t>(v)][static_cast<std::size_t>(i)] =
            static_cast<short>(in_disc ? u : 0);
        result.inside[static_cast<std::size_t>(v)][static_cast<std::size_t>(i)] =
            static_cast<short>(in_disc ? 1 : 0);
      }
    }
    return result;
  }();
  return weights;
}

void LoadRow(const uchar* first, std::array<cv::v_int16x8, 4>& pixels) {
  cv::v_uint16x8 parts[4];
  cv::v_expand(cv::v_load(first), parts[0], parts[1]);
  cv::v_expand(cv::v_load(first + 16), parts[2], parts[3]);
  for (int k = 0; k < 4; ++k)
    pixels[static_cast<std::size_t>(k)] = cv::v_reinterpret_as_s16(parts[k]);
}

std::pair<int, int> DiscMomentsSimd(const uchar* center, int step) {
  const DiscRowWeights& weights = RowWeights();
  const uchar* first = center - kHalfPatchSize;
  cv::v_int32x4 m10 = cv::v_setzero_s32();
  cv::v_int32x4 m01 = cv::v_setzero_s32();
  std::array<cv::v_int16x8, 4> below;
  std::array<cv::v_int16x8, 4> above;
  LoadRow(first, below);
  for (int k = 0; k < 4; ++k) {
    m10 += cv::v_dotprod(below[static_cast<std::size_t>(k)],
                         cv::v_load(weights.arm[0].data() + 8 * k));
  }
  for (int v = 1; v <= kHalfPatchSize; ++v) {
    LoadRow(first + v * step, below);
    LoadRow(first - v * step, above);
    const short* arm = weights.arm[static_cast<std::size_t>(v)].data();
    const short* inside = weights.inside[static_cast<std::size_t>(v)].data();
    cv::v_int32x4 difference = cv::v_setzero_s32();
    for (std::size_t k = 0; k < 4; ++k) {
      m10 += cv::v_dotprod(below[k] + above[k], cv::v_load(arm + 8 * k));
      difference += cv::v_dotprod(below[k] - above[k], cv::v_load(inside + 8 * k));
    }
    m01 += difference * cv::v_setall_s32(v);
  }
  return {cv::v_reduce_sum(m10), cv::v_reduce_sum(m01)};
}
#endif

}  // namespace

void ComputeOrientation(const cv::Mat& level_image, std::vector<cv::KeyPoint>& points) {
  const int step = static_cast<int>(level_image.step1());
  for (auto& point : points) {
    const int x = cvRound(point.pt.x);
    const uchar* center = &level_image.at<uchar>(cvRound(point.pt.y), x);
#if CV_SIMD128
    // The vector rows read one pixel past the disc on the right.
    const auto [m10, m01] = x + kHalfPatchSize + 1 < level_image.cols
                                ? DiscMomentsSimd(center, step)
                                : DiscMoments(center, step);
#else
    const auto [m10, m01] = DiscMoments(center, step);
#endif
    point.angle = cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
  }
}

}  // namespace noctua::features
