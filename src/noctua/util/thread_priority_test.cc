#include "noctua/util/thread_priority.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

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

#if defined(__linux__)
TEST(ThreadPriority, MovesTheCallingThreadOnlyToTheIdleClass) {
  int policy = -1;
  bool changed = false;
  std::thread worker([&] {
    changed = RunThisThreadWhenIdle();
    policy = sched_getscheduler(0);
  });
  worker.join();
  ASSERT_TRUE(changed);
  EXPECT_EQ(policy, SCHED_IDLE);
  EXPECT_NE(sched_getscheduler(0), SCHED_IDLE);
}
#endif

}  // namespace
}  // namespace noctua
