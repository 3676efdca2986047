#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <span>

namespace canalid::core {

/// Smallest and largest supported LFSR order n (period 2^n - 1).
inline constexpr int kMinLfsrOrder = 2;
inline constexpr int kMaxLfsrOrder = 31;

/// Feedback taps of the maximal-length LFSR of order n (2 <= n <= 31), largest first.
/// The table is Xilinx application note XAPP052 (P. Alfke, "Efficient Shift Registers, LFSR
/// Counters, and Long Pseudo-Random Sequence Generators", 1996, table 3) for n >= 3, and
/// x^2 + x + 1 for n = 2.  Taps {n, k, ...} define the recurrence over GF(2)
///   a(t) = a(t-n) XOR a(t-k) XOR ...
/// whose characteristic polynomial x^n + x^(n-k) + ... + 1 is the reciprocal of the listed
/// primitive polynomial x^n + x^k + ... + 1 (also primitive), so every nonzero start state gives
/// the full period 2^n - 1.  @throws std::invalid_argument if order is outside [2, 31].
std::span<const int> LfsrTaps(int order);

/// Maximal-length binary sequence (m-sequence) of order n as +-1 values (bit 1 -> +1, 0 -> -1).
/// Over one period of 2^n - 1 values there are 2^(n-1) values +1 and 2^(n-1) - 1 values -1, and the
/// periodic autocorrelation sum_t s(t) s(t+k) is 2^n - 1 at lag 0 and -1 at every other lag.
/// No allocation; Next() is a few bit operations.
class MaximalLengthSequence final {
 public:
  /// @param seed start state: the low `order` bits hold a(t-1) (bit 0) .. a(t-n) (bit n-1); must
  ///        be nonzero in those bits.  @throws std::invalid_argument on a bad order or seed.
  explicit MaximalLengthSequence(int order, std::uint32_t seed = 1);
  /// Advances one clock and returns the new value a(t) as +1 or -1.
  int Next();
  int order() const { return order_; }
  /// 2^order - 1 clocks.
  std::int64_t period() const { return (std::int64_t{1} << order_) - 1; }
  /// The register after the last Next() (the n most recent bits, newest in bit 0).
  std::uint32_t state() const { return state_; }

 private:
  int order_;
  std::uint32_t tap_mask_;
  std::uint32_t state_mask_;
  std::uint32_t state_;
};

/// A PRBS test signal for a flow input.
///   plain:       u(k) = nominal + amplitude * s(floor(k / clock_period_samples))
///   integrated:  u(k) = nominal + amplitude * sum_{j=0..k} s(floor(j / clock_period_samples))
/// where s is the +-1 m-sequence of `order` started from `seed`.  In integrated mode (for plants
/// that integrate their input, e.g. the LPV paper's pump voltage) `amplitude` is the change of u
/// per sample, the signal starts at nominal + amplitude * s(0), and it drifts by
/// + amplitude * clock_period_samples over each full period (one more +1 than -1).
struct PrbsSignalSpec {
  double nominal = 0.0;          ///< centre value (e.g. m3/s)
  double amplitude = 1.0;        ///< level offset (plain) or per-sample increment (integrated), > 0
  int clock_period_samples = 1;  ///< each bit is held this many samples, >= 1
  int order = 7;                 ///< LFSR order, 2..31
  std::uint32_t seed = 1;        ///< nonzero LFSR start state (see MaximalLengthSequence)
  bool integrate = false;
  /// @throws std::invalid_argument naming the field, the value and the allowed range.
  void Validate() const;
};

/// Sample-by-sample PRBS source (the online experiment path): no allocation after construction.
class PrbsGenerator final {
 public:
  /// @throws std::invalid_argument if the spec is invalid.
  explicit PrbsGenerator(const PrbsSignalSpec& spec);
  /// The next sample u(k), k = 0, 1, ...
  double Next();
  /// Samples in one full PRBS period: (2^order - 1) * clock_period_samples.
  std::int64_t period_samples() const;
  const PrbsSignalSpec& spec() const { return spec_; }

 private:
  PrbsSignalSpec spec_;
  MaximalLengthSequence sequence_;
  int held_value_ = 0;
  int samples_left_in_clock_ = 0;
  double sum_ = 0.0;
};

/// The first num_samples samples of the signal (see PrbsSignalSpec).
/// @throws std::invalid_argument if the spec is invalid or num_samples < 0.
Eigen::VectorXd GeneratePrbs(const PrbsSignalSpec& spec, Eigen::Index num_samples);

}  // namespace canalid::core
