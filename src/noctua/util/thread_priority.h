#pragma once

namespace noctua {

// Priorities for work no frame waits for, so that on a machine with fewer cores than busy threads
// the threads a frame waits for get the cores first. Each applies to the calling thread only and
// is best effort: a thread may always lower its own priority, and where the system offers no
// per-thread priority nothing changes (false).

// Lowers the calling thread's priority by `nice_steps` (Linux nice values): it still gets a
// share of a busy core, smaller by about 1.25× per step.
bool LowerThisThreadsPriority(int nice_steps);

// Moves the calling thread to the idle class (Linux SCHED_IDLE): it runs only on time the other
// threads leave.
bool RunThisThreadWhenIdle();

// The calling thread's nice value (0 unless lowered); 0 where there is none.
int ThisThreadsNice();

}  // namespace noctua
