#pragma once
#include <cstdint>
#include <vector>

#include "core/numerics/ring_buffer.h"
#include "core/online/estimator_bank.h"
#include "core/online/online_gl_regressor.h"
#include "core/online/rls.h"

namespace canalid::core {

struct OnlineFractionalOptions {
  double sample_time_s = 1.0;  ///< h > 0
  /// The alpha grid, each in (0, 2); one estimator per value.
  std::vector<double> alphas{0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4};
  int memory_samples = 200;  ///< GL short memory L >= 1
  int delay_samples = 0;     ///< d >= 0 (known; a delay bank is the ID/ARX banks' job)
  /// Per alpha, n = 2.  Its box is replaced by 0 <= theta1 <= 1 - 1e-9 (T >= 0, finite).
  RlsOptions rls;
  BankSelectorOptions selector;
  double input_abs_max = 1e9;
  double output_abs_max = 1e9;
  /// Output error (parallel model, Landau): each candidate's GL sum runs over its own simulated
  /// output x(k) = theta' phi(k) instead of the measured y, so the a-priori error is the
  /// simulation error the batch fit minimises and the selector picks alpha by it.  Equation error
  /// (false) weights the fit by the model's high-pass (1 + c) + c sum w_j q^-j and on oversampled
  /// records prefers an extrapolator: on the lab flume's gate step (Ts 0.15 s, T ~ 5 s^alpha) its
  /// theta1 ran to the projection bound (T ~ 1e8, K ~ -4e9) at every alpha.
  bool output_error = false;

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

struct FractionalSnapshot {
  bool valid = false;
  std::int64_t sample = -1;
  double alpha = 0.0;
  double gain = 0.0;             ///< K
  double time_constant_s = 0.0;  ///< T (in s^alpha): T = c h^alpha
  double theta1 = 0.0;           ///< c / (1 + c)
  double theta2 = 0.0;           ///< K / (1 + c)
  double theta1_std = 0.0;
  double theta2_std = 0.0;
  double gain_std = 0.0;             ///< first order, from the full covariance sigma2 P
  double time_constant_std_s = 0.0;  ///< first order (T depends on theta1 only)
  double condition_number = 1.0;     ///< of P (exact: 2 x 2)
  double information_min = 0.0;      ///< smallest eigenvalue of P^-1, 1 / lambda_max(P)
  double prediction_error = 0.0;
  double innovation_std = 0.0;
  double loss = 0.0;
  RlsHealth health;
};

struct FractionalBankHealth {
  std::int64_t samples = 0;
  std::int64_t bad_inputs = 0;   ///< replaced by the last good input
  std::int64_t bad_outputs = 0;  ///< replaced in the history by the selected model's prediction
  int switches = 0;
};

/// Online fractional first-order model K e^{-d h s} / (1 + T s^alpha) over an alpha grid.  With the
/// GL1 discretisation (c = T h^-alpha)
///   y(k) (1 + c) + c sum_{j=1..L} w_j y(k-j) = K u(k-d)
/// is linear in theta = [c/(1+c), K/(1+c)]:  y(k) = theta1 G_y(k) + theta2 u(k-d) with
/// G_y(k) = -sum_{j=1..L} w_j y(k-j).  Recovered: c = theta1 / (1 - theta1),
/// K = theta2 / (1 - theta1), T = c h^alpha.  Signals are deviations from an equilibrium (no
/// offset term) starting from rest.  One Rls<2> per alpha (theta1 projected onto [0, 1)), the
/// BankSelector picks alpha.  A bad input is replaced by the last good one; a bad output skips
/// the update and enters the GL history as the selected model's prediction, so that it does not
/// poison the next L regressors.  Allocates only in the constructor.  Deterministic.
class OnlineFractionalBank final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineFractionalBank(const OnlineFractionalOptions& options);

  bool Update(double u, double y);

  FractionalSnapshot Snapshot() const;
  FractionalSnapshot CandidateSnapshot(int index) const;  ///< index into options().alphas
  int selected_index() const { return selector_.selected(); }
  int num_candidates() const { return static_cast<int>(estimators_.size()); }
  const FractionalBankHealth& health() const { return health_; }
  const OnlineFractionalOptions& options() const { return options_; }

 private:
  OnlineFractionalOptions options_;
  std::vector<OnlineGlRegressor> regressors_;
  std::vector<RingBuffer<double>> simulated_;  // output_error: each candidate's x(k-1), x(k-2)...
  std::vector<Rls<2>> estimators_;
  std::vector<double> predictions_;
  BankSelector selector_;
  RingBuffer<double> u_history_;
  RingBuffer<double> y_history_;
  double u_good_ = 0.0;
  std::int64_t k_ = -1;
  FractionalBankHealth health_;
};

}  // namespace canalid::core
