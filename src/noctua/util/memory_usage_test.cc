#include "noctua/util/memory_usage.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace noctua {
namespace {

TEST(MemoryUsage, TouchingMemoryRaisesResidentAndPeak) {
  const std::optional<double> before = ResidentMemoryMb();
  ASSERT_TRUE(before.has_value());
  EXPECT_GT(*before, 0.0);
  // 64 MB written page by page must become resident.
  constexpr std::size_t kBytes = 64'000'000;
  auto block = std::make_unique<char[]>(kBytes);
  std::memset(block.get(), 1, kBytes);
  const std::optional<double> during = ResidentMemoryMb();
  ASSERT_TRUE(during.has_value());
  EXPECT_GT(*during, *before + 50.0);
  EXPECT_GE(PeakResidentMemoryMb(), *during - 1.0);
  EXPECT_EQ(block[kBytes - 1], 1);
}

}  // namespace
}  // namespace noctua
