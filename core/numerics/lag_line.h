#pragma once
#include <cassert>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::core {

/// The last `capacity` values of a series, by lag (0 = the newest), laid out so that every run
/// of lags is one contiguous array: Lags()[lag] is the value pushed `lag` pushes ago, for
/// 0 <= lag < capacity, whatever the position in the ring.  A dot product with weights over the
/// lags, or a loop over a bank's delays, then reads one array without a wrap.  A mirrored ring:
/// each value is written twice, at its slot and `capacity` slots further on.  Lags not yet
/// pushed read 0.  Allocates only in the constructor; pure, not thread-safe.
class LagLine final {
 public:
  /// @throws std::invalid_argument if capacity < 1.
  explicit LagLine(int capacity) : capacity_(capacity) {
    if (capacity < 1) {
      throw std::invalid_argument("LagLine: capacity = " + std::to_string(capacity) +
                                  " must be >= 1");
    }
    data_.assign(2 * static_cast<std::size_t>(capacity), 0.0);
  }

  void Push(double value) {
    head_ = head_ == 0 ? capacity_ - 1 : head_ - 1;
    const auto slot = static_cast<std::size_t>(head_);
    data_[slot] = value;
    data_[slot + static_cast<std::size_t>(capacity_)] = value;
  }
  /// lags()[lag], lag in [0, capacity): the value pushed `lag` pushes ago.
  const double* Lags() const { return data_.data() + head_; }
  double operator[](int lag) const {
    assert(lag >= 0 && lag < capacity_);
    return Lags()[lag];
  }
  int capacity() const { return capacity_; }
  /// Back to no value pushed (every lag reads 0).
  void Reset() {
    data_.assign(data_.size(), 0.0);
    head_ = 0;
  }

 private:
  int capacity_;
  int head_ = 0;
  std::vector<double> data_;
};

}  // namespace canalid::core
