#pragma once
#include <chrono>

namespace canalid::daemon {

/// Seconds on the steady clock (intervals, deadlines, uptime).
inline double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Seconds since the epoch (message and file timestamps).
inline double WallNowS() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// A steady-clock duration (timer expiry) from seconds.
inline std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

}  // namespace canalid::daemon
