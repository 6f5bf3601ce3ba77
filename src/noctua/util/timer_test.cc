#include "noctua/util/timer.h"

#include <gtest/gtest.h>

namespace noctua {
namespace {

TEST(Summarize, MedianOfOddAndEvenCounts) {
  EXPECT_DOUBLE_EQ(Summarize({5.0, 1.0, 3.0}).median_ms, 3.0);
  EXPECT_DOUBLE_EQ(Summarize({4.0, 1.0, 3.0, 2.0}).median_ms, 2.5);
}

TEST(Summarize, PercentilesAndMaximum) {
  std::vector<double> samples;
  for (int i = 0; i <= 100; ++i) samples.push_back(static_cast<double>(100 - i));
  const TimingSummary summary = Summarize(samples);
  EXPECT_EQ(summary.count, 101);
  EXPECT_DOUBLE_EQ(summary.p10_ms, 10.0);
  EXPECT_DOUBLE_EQ(summary.p90_ms, 90.0);
  EXPECT_DOUBLE_EQ(summary.p95_ms, 95.0);
  EXPECT_DOUBLE_EQ(summary.max_ms, 100.0);
}

TEST(Summarize, EmptyGivesZeros) {
  const TimingSummary summary = Summarize({});
  EXPECT_EQ(summary.count, 0);
  EXPECT_EQ(summary.median_ms, 0.0);
}

}  // namespace
}  // namespace noctua
