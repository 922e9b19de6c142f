// CPU time of the calling thread, for reporting what a computation cost (cpu_s in responses,
// the studies in bench/). Never an input to physics: simulated time is tick * dt.
#ifndef SPORTSIM_SIM_CORE_CPU_CLOCK_H_
#define SPORTSIM_SIM_CORE_CPU_CLOCK_H_

#include <time.h>

namespace sportsim {

/// Seconds of CPU the calling thread has used (CLOCK_THREAD_CPUTIME_ID).
inline double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_CPU_CLOCK_H_
