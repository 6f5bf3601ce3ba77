#include "noctua/util/thread_priority.h"

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#endif

namespace noctua {

#if defined(__linux__)

int ThisThreadsNice() {
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
  return errno == 0 ? nice : 0;
}

bool LowerThisThreadsPriority(int nice_steps) {
  // On Linux PRIO_PROCESS with a thread id sets that thread only.
  return setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), ThisThreadsNice() + nice_steps) ==
         0;
}

bool RunThisThreadWhenIdle() {
  sched_param param{};
  param.sched_priority = 0;
  return pthread_setschedparam(pthread_self(), SCHED_IDLE, &param) == 0;
}

#else

int ThisThreadsNice() { return 0; }
bool LowerThisThreadsPriority(int /*nice_steps*/) { return false; }
bool RunThisThreadWhenIdle() { return false; }

#endif

}  // namespace noctua
