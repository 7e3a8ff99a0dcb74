// Wall-clock time of a stage, for the timing figures in frames.csv and metrics.json.
#pragma once

#include <chrono>

namespace driftlab {

using SteadyClock = std::chrono::steady_clock;

/// Milliseconds from t0 to now.
inline double ms_since(SteadyClock::time_point t0) {
  return std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
}

/// Seconds from t0 to now.
inline double seconds_since(SteadyClock::time_point t0) {
  return std::chrono::duration<double>(SteadyClock::now() - t0).count();
}

/// Started when made; restart() begins a new lap.
class Stopwatch {
 public:
  double ms() const { return ms_since(t0_); }
  double seconds() const { return seconds_since(t0_); }
  void restart() { t0_ = SteadyClock::now(); }

 private:
  SteadyClock::time_point t0_ = SteadyClock::now();
};

}  // namespace driftlab
