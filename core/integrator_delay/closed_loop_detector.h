#pragma once
#include <cstdint>

namespace canalid::core {

/// FitIntegratorDelay's closed-loop test computed sample by sample with running sums, so that an
/// online estimator can take the same decision without storing the record:
///   closed loop  <=>  std(q_out) > 0.02 std(q_in)  and  r > 0.3,
/// r the correlation of the outflow and the level, both with their least-squares line (in the
/// sample index) removed.  The inflow's std is over every sample given to AddInflow; the
/// outflow's std and r over the samples given to AddOutflowLevel (FitIntegratorDelay: k0..N-1, so
/// the same samples give the same r to rounding).  Sums are taken relative to the first sample, so
/// the level's offset does not cancel digits.  O(1) per sample, no allocation.  Pure.
class ClosedLoopDetector final {
 public:
  static constexpr double kOutflowMovesRatio = 0.02;  ///< std(q_out) / std(q_in) threshold
  static constexpr double kCorrelationMin = 0.3;      ///< r threshold (signed)

  void AddInflow(double q_in_m3s);
  void AddOutflowLevel(double q_out_m3s, double level_m);

  std::int64_t inflow_samples() const { return in_.n; }
  std::int64_t samples() const { return n_; }
  /// r (0 when either detrended series is constant or fewer than 3 samples).
  double OutflowLevelCorrelation() const;
  bool OutflowMoves() const;
  /// OutflowMoves() and r > kCorrelationMin: an outflow that follows the level rises with it; one
  /// moved on its own (a second structure's experiment, a pump) lowers the level it drains, r < 0.
  bool ClosedLoop() const;

 private:
  struct Moments {
    std::int64_t n = 0;
    double first = 0.0;
    double sum = 0.0;  // of x - first
    double sum2 = 0.0;
    void Add(double x);
    double Variance() const;
  };
  Moments in_;
  Moments out_;
  std::int64_t n_ = 0;
  double level_first_ = 0.0;
  // Relative to the first sample: t = sample index, x = q_out - first, y = level - first.
  double st_ = 0.0;
  double stt_ = 0.0;
  double sy_ = 0.0;
  double syy_ = 0.0;
  double sxt_ = 0.0;
  double syt_ = 0.0;
  double sxy_ = 0.0;
};

}  // namespace canalid::core
