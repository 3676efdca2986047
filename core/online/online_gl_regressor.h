#pragma once
#include <vector>

#include "core/numerics/ring_buffer.h"

namespace canalid::core {

/// Short-memory Grunwald-Letnikov sum for the online fractional estimators:
///   S(k) = sum_{j=1..min(L, available)} w_j x(k-j),  w_0 = 1, w_j = w_{j-1} (1 - (alpha + 1) / j),
/// (w_j = (-1)^j binom(alpha, j)), so D^alpha x(k) ~ h^-alpha (x(k) + S(k)).  Samples before the
/// first one are taken as zero (the signal starts from rest).  Weights are computed once in the
/// constructor; Sum never allocates.  Pure.
class OnlineGlRegressor final {
 public:
  /// @param alpha 0 < alpha < 2.  @param memory L >= 1.
  /// @throws std::invalid_argument naming the argument out of range.
  OnlineGlRegressor(double alpha, int memory);

  /// S(k) with history[0] = x(k-1), history[1] = x(k-2), ...
  double Sum(const RingBuffer<double>& history) const;

  double alpha() const { return alpha_; }
  int memory() const { return static_cast<int>(reversed_.size()); }
  /// w_j, 0 <= j <= L.
  double weight(int j) const {
    return j == 0 ? 1.0 : reversed_[reversed_.size() - static_cast<std::size_t>(j)];
  }

 private:
  double alpha_;
  // w_L, ..., w_1 (w_0 = 1 is not kept): the weights in the order of the history's storage,
  // oldest first (Sum's dot products run over both in the same direction, so Eigen vectorises
  // them).
  std::vector<double> reversed_;
};

}  // namespace canalid::core
