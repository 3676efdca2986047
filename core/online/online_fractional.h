#pragma once
#include <cstdint>
#include <vector>

#include "core/numerics/ring_buffer.h"
#include "core/online/estimator_bank.h"
#include "core/online/rls.h"

namespace canalid::core {

struct OnlineFractionalOptions {
  double sample_time_s = 1.0;  ///< h > 0
  /// The alpha grid, each in (0, 2).
  std::vector<double> alphas{0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4};
  int memory_samples = 200;  ///< GL short memory L >= 1
  int delay_samples = 0;     ///< d >= 0 (known; a delay bank is the ID/ARX banks' job)
  /// Per candidate, n = 2: theta = [K, offset].
  RlsOptions rls;
  /// kResidual (the default) is the output-error loss of each candidate over the samples so far
  /// (with lambda = 1 and a large P0), so the bank picks the candidate a batch output-error scan
  /// of the same grid would; the loss of the selected candidate's neighbours refines T.
  BankSelectorOptions selector{.criterion = BankCriterion::kResidual};
  double input_abs_max = 1e9;
  double output_abs_max = 1e9;

  /// The characteristic times T^(1/alpha) the grid holds at every alpha: kTimePointsPerDecade
  /// per decade from h to max(L, 10) h (beyond the memory the GL sum no longer follows them).
  static constexpr int kTimePointsPerDecade = 10;
  /// Largest alphas x memory x time points (the simulated outputs the bank keeps).
  static constexpr double kMaxHistoryValues = 2e7;

  int num_time_points() const;
  /// The grid's i-th characteristic time, s.
  double characteristic_time_s(int i) const;

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

struct FractionalSnapshot {
  bool valid = false;
  std::int64_t sample = -1;
  double alpha = 0.0;
  double gain = 0.0;             ///< K
  double time_constant_s = 0.0;  ///< T (in s^alpha) = tc^alpha
  double offset = 0.0;           ///< the output at rest, as a deviation from the first sample
  double gain_std = 0.0;
  /// From the loss's curvature in log tc; NaN at a grid edge or when the selector does not
  /// compare least-squares losses (an RLS method that is not least squares).
  double time_constant_std_s = 0.0;
  double offset_std = 0.0;
  /// The selected candidate's tc is the grid's first or last (T is then a bound, not a fit), or,
  /// with several alphas, its alpha is the first or last.
  bool at_grid_edge = false;
  double condition_number = 1.0;  ///< of the selected candidate's P (exact: 2 x 2)
  double information_min = 0.0;   ///< smallest eigenvalue of P^-1, 1 / lambda_max(P)
  double prediction_error = 0.0;
  double innovation_std = 0.0;
  double loss = 0.0;
  RlsHealth health;
};

struct FractionalBankHealth {
  std::int64_t samples = 0;
  std::int64_t bad_inputs = 0;   ///< replaced by the last good input
  std::int64_t bad_outputs = 0;  ///< skipped (the simulations run on the input alone)
  int switches = 0;
};

/// Online fractional first-order model y = K e^{-d h s} / (1 + T s^alpha) u + offset by output
/// error over a grid of alpha and of the characteristic time tc = T^(1/alpha).  Each candidate
/// (alpha, c = (tc / h)^alpha) simulates the unit-gain model with the GL1 discretisation
///   x(k) (1 + c) + c sum_{j=1..L} w_j x(k-j) = u(k-d)
/// on the input alone, so its x is exact (no estimate feeds back into it), and the model is
/// linear in theta = [K, offset]:  y(k) = K x(k) + offset.  One Rls<2> per candidate fits theta;
/// its residual is the candidate's output-error loss, the loss a batch output-error fit
/// minimises.  The selector picks the candidate; the parabola through the loss of it and its two
/// tc neighbours refines tc (and K, offset by the same interpolation) between grid points.
/// Signals are deviations from the first sample; the offset absorbs an equilibrium that the
/// first sample misses.  A bad input is replaced by the last good one; a bad output skips the
/// updates.  The histories of all tc at one alpha sit side by side, so one matrix-vector product
/// per alpha gives every GL sum.  Allocates only in the constructor.  Deterministic.
class OnlineFractionalBank final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineFractionalBank(const OnlineFractionalOptions& options);

  bool Update(double u, double y);

  /// The selected candidate, with tc refined between grid points.
  FractionalSnapshot Snapshot() const;
  /// Candidate `index` = alpha index x num_time_points() + time index, at its grid point.
  FractionalSnapshot CandidateSnapshot(int index) const;
  int selected_index() const { return selector_.selected(); }
  int num_candidates() const { return static_cast<int>(estimators_.size()); }
  int num_time_points() const { return time_points_; }
  const FractionalBankHealth& health() const { return health_; }
  const OnlineFractionalOptions& options() const { return options_; }

 private:
  double Loss(int index) const { return selector_.loss(index); }
  void FillCovarianceHealth(const Rls<2>& rls, FractionalSnapshot& s) const;

  OnlineFractionalOptions options_;
  int time_points_;
  int memory_;
  std::vector<double> c_;         // per candidate
  std::vector<double> reversed_;  // per alpha: w_L .. w_1 (oldest sample first)
  // Per alpha, a ring of L samples, each the time_points_ simulated outputs side by side.
  std::vector<double> history_;
  int head_ = 0;              // the ring's next row (the oldest once full)
  int filled_ = 0;            // rows written, <= L
  std::vector<double> sums_;  // time_points_: the GL sums of one alpha
  std::vector<double> x_;     // per candidate: x(k)
  std::vector<Rls<2>> estimators_;
  BankSelector selector_;
  RingBuffer<double> u_history_;
  double u_good_ = 0.0;
  std::int64_t k_ = -1;
  FractionalBankHealth health_;
};

}  // namespace canalid::core
