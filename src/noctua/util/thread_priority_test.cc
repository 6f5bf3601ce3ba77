#include "noctua/util/thread_priority.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

namespace noctua {
namespace {

TEST(ThreadPriority, LowersTheCallingThreadOnly) {
  const int before = ThisThreadsNice();
  int lowered = before;
  bool changed = false;
  std::thread worker([&] {
    changed = LowerThisThreadsPriority(5);
    lowered = ThisThreadsNice();
  });
  worker.join();
  ASSERT_TRUE(changed);
  EXPECT_EQ(lowered, std::min(before + 5, 19));
  EXPECT_EQ(ThisThreadsNice(), before);
}

}  // namespace
}  // namespace noctua
