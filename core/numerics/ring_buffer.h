#pragma once
#include <cassert>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::core {

/// Fixed-capacity history of the last `capacity` values; the storage is allocated once in the
/// constructor, Push overwrites the oldest value.  Lag 0 is the newest value.
/// Pure, not thread-safe.
template <typename T>
class RingBuffer final {
 public:
  /// @throws std::invalid_argument if capacity < 1.
  explicit RingBuffer(int capacity) {
    if (capacity < 1) {
      throw std::invalid_argument("RingBuffer: capacity = " + std::to_string(capacity) +
                                  " must be >= 1");
    }
    data_.assign(static_cast<std::size_t>(capacity), T{});
  }

  void Push(const T& value) {
    head_ = head_ + 1 == capacity() ? 0 : head_ + 1;
    data_[static_cast<std::size_t>(head_)] = value;
    if (size_ < capacity()) ++size_;
  }

  /// The value pushed `lag` pushes ago.  @pre 0 <= lag < size().
  const T& operator[](int lag) const {
    assert(lag >= 0 && lag < size_);
    int i = head_ - lag;
    if (i < 0) i += capacity();
    return data_[static_cast<std::size_t>(i)];
  }

  /// The newest `count` values, oldest first, as at most two runs of storage: `older` then
  /// `newer` (`older` is empty when the values do not wrap).  @pre 0 <= count <= size().
  struct Runs {
    std::span<const T> older;
    std::span<const T> newer;
  };
  Runs Chronological(int count) const {
    assert(count >= 0 && count <= size_);
    const auto base = data_.data();
    const int start = head_ - count + 1;
    if (start >= 0) {
      return {{}, {base + start, static_cast<std::size_t>(count)}};
    }
    return {{base + capacity() + start, static_cast<std::size_t>(-start)},
            {base, static_cast<std::size_t>(head_ + 1)}};
  }

  int size() const { return size_; }
  int capacity() const { return static_cast<int>(data_.size()); }
  bool full() const { return size_ == capacity(); }
  void Clear() {
    size_ = 0;
    head_ = -1;
  }

 private:
  std::vector<T> data_;
  int head_ = -1;
  int size_ = 0;
};

}  // namespace canalid::core
