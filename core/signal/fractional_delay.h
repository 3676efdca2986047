#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// The longest delay, in samples, that a simulator accepts: delay lines and plants keep a ring of
/// that many inputs (8 bytes each, so at most 80 MB), and the whole count must fit an int.
inline constexpr double kMaxDelaySamples = 1e7;

/// A delay tau = (whole_samples + fraction) Ts, 0 <= fraction < 1.  Over the sample interval
/// [k Ts, (k+1) Ts) a zero-order-held input u delayed by tau equals u[k - whole - 1] during the
/// first fraction * Ts and u[k - whole] afterwards (the "delayed ZOH split").
struct ZohDelaySplit {
  int whole_samples = 0;
  double fraction = 0.0;
};

/// @throws std::invalid_argument unless delay_s >= 0 and sample_time_s > 0 (finite), or when the
///         delay exceeds kMaxDelaySamples (1e7) samples.
ZohDelaySplit SplitZohDelay(double delay_s, double sample_time_s);

/// Ring buffer of the last whole_samples + 2 inputs (zero before the first Push), giving the two
/// inputs of the delayed ZOH split.  Allocates only in the constructor.
class ZohDelayLine final {
 public:
  explicit ZohDelayLine(int whole_samples);
  /// Stores u[k]; afterwards previous() = u[k - d - 1] and current() = u[k - d].
  void Push(double input) {
    head_ = head_ + 1 == size_ ? 0 : head_ + 1;
    buffer_(head_) = input;
  }
  double current() const { return At(size_ - 2); }
  double previous() const { return At(size_ - 1); }
  void Reset() { buffer_.setZero(); }

 private:
  double At(int age) const {
    const int index = head_ - age;
    return buffer_(index < 0 ? index + size_ : index);
  }
  Eigen::VectorXd buffer_;
  int size_;
  int head_ = 0;
};

}  // namespace canalid::core
