#pragma once
// What every benchmark reports beside its result: process CPU time (comparable on a loaded
// machine, where wall time is not), the load average it ran at, and the peak resident memory.
#include <sys/resource.h>

#include <ctime>
#include <fstream>

namespace tomodem::measure {

inline double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// One-minute load average.
inline double load_average() {
  std::ifstream in("/proc/loadavg");
  double l = 0;
  in >> l;
  return l;
}

inline double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

}  // namespace tomodem::measure
