// CPU clocks for benchmarks and measurement tools.
//
// Contract: threadCpuSeconds() is the CPU time of the calling thread,
// processCpuSeconds() that of the whole process (all threads: llvmpipe's
// rasterizer threads count there, not in the thread clock), both in seconds
// from an arbitrary origin (POSIX clock_gettime). Why CPU time: the machines
// we measure on are shared, and wall time would measure the other processes
// too; differences of two readings are what a caller uses.
#pragma once

#include <time.h>

namespace thinlod {

inline double cpuClockSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline double threadCpuSeconds() { return cpuClockSeconds(CLOCK_THREAD_CPUTIME_ID); }
inline double processCpuSeconds() { return cpuClockSeconds(CLOCK_PROCESS_CPUTIME_ID); }

}  // namespace thinlod
