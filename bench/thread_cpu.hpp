// CPU seconds of the calling thread: what the benchmarks time, so that other
// processes on a shared machine do not count (docs/performance.md).
#pragma once

#include <ctime>

namespace emdae::bench {

inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace emdae::bench
