#pragma once
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::drivers {

/// Bounded exponential backoff between reconnect attempts:
///   delay_n = min(initial_s * 2^n, max_s),  n = failures since the last Reset().
/// Pure, no clock.
class ReconnectBackoff final {
 public:
  /// @throws std::invalid_argument unless 0 < initial_s <= max_s (finite).
  ReconnectBackoff(double initial_s, double max_s) : initial_s_(initial_s), max_s_(max_s) {
    if (!(initial_s > 0.0 && std::isfinite(max_s) && initial_s <= max_s)) {
      throw std::invalid_argument("reconnect backoff: need 0 < initial_s (" +
                                  std::to_string(initial_s) + ") <= max_s (" +
                                  std::to_string(max_s) + ")");
    }
  }
  /// The delay before the next attempt after one more failure.
  double NextDelay() {
    const double delay = std::min(initial_s_ * std::ldexp(1.0, std::min(failures_, 60)), max_s_);
    ++failures_;
    return delay;
  }
  void Reset() { failures_ = 0; }
  int failures() const { return failures_; }

 private:
  double initial_s_;
  double max_s_;
  int failures_ = 0;
};

}  // namespace canalid::drivers
