#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace canalid::dashboard {

/// One point of a time series: time (s since the epoch), value and its standard deviation (NaN
/// when it has none).  16 bytes.
struct SeriesPoint {
  double t = 0.0;
  float value = 0.0F;
  float sd = NAN;
};

/// The last points of one time series, bounded twice: by count (the ring's capacity, allocated as
/// points come) and by age (points older than `window_s` before the newest are dropped).  Every
/// point gets a sequence number (0, 1, ... in order of arrival), so a reader can ask for what came
/// after the last point it saw.
class SeriesRing {
 public:
  SeriesRing(std::size_t capacity, double window_s) : capacity_(capacity), window_s_(window_s) {}

  void Append(const SeriesPoint& point) {
    if (capacity_ == 0) return;
    if (points_.size() < capacity_) {
      // Grown by doubling up to the capacity, never past it (a vector's own growth could
      // allocate up to twice the capacity).
      if (points_.size() == points_.capacity()) {
        points_.reserve(std::min(capacity_, std::max<std::size_t>(16, 2 * points_.size())));
      }
      points_.push_back(point);
    } else {
      // The oldest slot: an aged-out one if any, else the oldest point held (evicted).
      points_[head_] = point;
      head_ = (head_ + 1) % capacity_;
      if (dropped_in_place_ > 0) --dropped_in_place_;
    }
    ++appended_;
    while (size() > 1 && at(0).t < point.t - window_s_) Drop();
  }

  /// Points held now.
  std::size_t size() const { return points_.size() - dropped_in_place_; }
  /// The i-th point held, oldest first.
  const SeriesPoint& at(std::size_t i) const {
    return points_[(head_ + dropped_in_place_ + i) % points_.size()];
  }
  /// Sequence number of the next point to be appended (= points ever appended).
  std::int64_t appended() const { return appended_; }
  /// Sequence number of the oldest point held.
  std::int64_t first_sequence() const { return appended_ - static_cast<std::int64_t>(size()); }

 private:
  // Drops the oldest point held.  In a full ring the slot stays allocated and is counted as
  // dropped until it is overwritten; in a growing one the storage is compacted when half is dead.
  void Drop() {
    ++dropped_in_place_;
    if (points_.size() < capacity_ && dropped_in_place_ * 2 >= points_.size()) Compact();
  }
  void Compact() {
    std::vector<SeriesPoint> kept;
    kept.reserve(points_.size());
    for (std::size_t i = 0; i < size(); ++i) kept.push_back(at(i));
    points_.swap(kept);
    head_ = 0;
    dropped_in_place_ = 0;
  }

  std::size_t capacity_;
  double window_s_;
  std::vector<SeriesPoint> points_;
  std::size_t head_ = 0;              ///< index of the oldest slot once the ring is full
  std::size_t dropped_in_place_ = 0;  ///< oldest slots no longer held (aged out)
  std::int64_t appended_ = 0;
};

}  // namespace canalid::dashboard
