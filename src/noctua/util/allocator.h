#pragma once

namespace noctua::util {

// Makes the C library keep the large blocks a frame's processing frees, instead of handing them
// back to the kernel and faulting them in again on the next frame (glibc's mallopt: blocks up to
// 32 MiB come from the heap, and up to 256 MiB of free heap is kept). A 640×480 float image is
// 1.2 MB, above glibc's default 128 KiB mmap threshold, and the phase-congruency edge map makes
// dozens per frame: by default each is a fresh mmap whose pages fault in on first touch. glibc
// raises its threshold by itself only after it has freed a larger mmapped block, which is why
// loading an unrelated model (the detector) used to make the edge map three times faster
// (docs/benchmarks.md). Process-wide and irreversible; the `noctua` command calls it first thing,
// and a program that runs noctua on a stream of frames should do the same. No effect beyond
// glibc.
void KeepFrameBuffersInProcess();

}  // namespace noctua::util
