#pragma once

namespace noctua {

// Lowers the calling thread's scheduling priority by `nice_steps` (Linux nice values, per
// thread): for work no frame waits for, so that on a machine with fewer cores than busy threads
// the threads a frame waits for get the cores first. Other threads keep theirs. Returns false
// (nothing changed) where the system has no per-thread priority.
bool LowerThisThreadsPriority(int nice_steps);

// The calling thread's nice value (0 unless lowered); 0 where there is none.
int ThisThreadsNice();

}  // namespace noctua
