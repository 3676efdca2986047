#pragma once
#include <Eigen/Core>
#include <cstdint>

#include "core/online/rls.h"
#include "core/online/rls_iv.h"

namespace canalid::core {

/// Options of OnlineThreeStep.
struct ThreeStepOptions {
  /// m, order of the sensitivity model F (1..4; the method uses 4).
  int sensitivity_order = 4;
  /// Step (2)'s estimator (n = 2 m, padded to 8).  Forgetting, P0 and the sample guards apply.
  RlsOptions sensitivity;
  /// Step (2) by instrumental variables (IvRls) with the instrument
  /// z = [-t_hat(k-1)..-t_hat(k-m), input terms], t_hat the flow simulated through the current
  /// F_hat (the recursive form of the batch's IV refinement against the outflow meter's noise).
  /// Off by default: on the fixed-gate ASCE canal 2 pool 2 record at nk = 12 (the realization
  /// before the simulator's PRBS became core/signal/prbs.h's) the IV estimate was unstable on 638
  /// of 780 samples (instruments from a poor early F_hat are weak), least squares on 9; step 3
  /// gave 33407 m^2 (IV) and 34223 m^2 (LS) against 34113 m^2.
  bool sensitivity_iv = false;
  RlsOptions regression;  ///< step (3)'s estimator (n = 7); UD, lambda 1 by default
  /// Step (3) starts after this many samples (F_hat must have settled; an early F_hat from a
  /// handful of samples simulates a flow that would stay in a lambda = 1 fit for good).
  int warmup_samples = 100;
  /// Regressors of the integrated free responses of F_hat (its unknown initial state), as the
  /// batch does; false: only [Q_hat, 1, k].
  bool free_response_terms = true;
  /// Re-centring period of the integrated regressors and of k (samples; 0 = never).
  int recentre_samples = 0;

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// Online form of the three-step closed-loop method (Van den Hof & Schrama) for
/// one delay nk, the recursive twin of FitIntegratorDelay's closed-loop branch.  Per sample i = 0,
/// 1, ... (i = k - k0) with u(i) = q_in(k - nk) and the measured total flow t(i) = q_in(k - nk) -
/// q_out(k - 1):
///  (2) F_hat: t(i) = -sum_{j=1..m} a_j t(i-j) + sum_{j=0..m-1} b_j (u(i-j) - u(i-m)) + e, for
///      i >= m (zero DC gain by construction, as the batch), by RLS or IV-RLS;
///  (3) t_hat(i) = 0 for i < m, then the same recursion on t_hat with the current F_hat (the last
///      stable one: the AR part is checked by the Schur-Cohn step-down test); the free responses
///      f_r (f_r(i) = [i == r] for i < m, the AR recursion after); Q_hat(i) = sum_{l<=i} t_hat(l),
///      F_r(i) = sum_{l<=i} f_r(l);
///      y(i) = b Q_hat(i) + sum_r g_r F_r(i) + c + d i   by Rls<7>, from i = warmup_samples on.
/// With F_hat frozen (FreezeSensitivity), warmup 0, lambda 1 and a large P0, step (3) is the batch
/// least-squares fit on those rows.  area = Ts / b.  Allocates only in the constructor; Update
/// never allocates.  Deterministic.
class OnlineThreeStep final {
 public:
  static constexpr int kMaxOrder = 4;
  static constexpr int kSensitivityParams = 2 * kMaxOrder;
  static constexpr int kParams = 3 + kMaxOrder;  ///< [b, g_1..g_4, c, d]
  static constexpr int kOffset = kParams - 2;
  static constexpr int kDrift = kParams - 1;
  using SensitivityVector = Eigen::Matrix<double, kSensitivityParams, 1>;

  /// @throws std::invalid_argument on a bad option.
  explicit OnlineThreeStep(const ThreeStepOptions& options);

  /// Fixes F_hat to theta = [a_1..a_m, b_0..b_{m-1}] (the layout of
  /// IntegratorDelayFit::sensitivity_theta) and stops step (2).  Call before the first Update.
  /// @throws std::invalid_argument if m is not in 1..4, theta.size() != 2 m or theta not finite.
  void FreezeSensitivity(int order, const Eigen::Ref<const Eigen::VectorXd>& theta);

  /// One sample; flows must be finite (the caller replaces bad ones).  level_ok = false: no
  /// step-(3) update (the sensitivity and the integrators still advance).  Returns true when
  /// step (3) was updated.  Never throws, never allocates.
  bool Update(double delayed_inflow_m3s, double total_flow_m3s, double level_m, bool level_ok);

  double b() const { return fit_.theta()(0); }
  double c_m() const;  ///< offset at i = 0 (batch convention)
  double d_m() const { return fit_.theta()(kDrift); }
  /// Standard deviations from sigma2 P of b, c, d.
  void StandardDeviations(double& b_std, double& c_std_m, double& d_std_m) const;
  const Rls<kParams>& regression() const { return fit_; }
  /// The F_hat used by the simulation (the last stable estimate), padded with zeros.
  const SensitivityVector& sensitivity() const { return f_used_; }
  int order() const { return order_; }
  std::int64_t samples() const { return i_ + 1; }
  /// Times the estimate of F_hat was unstable and the previous one was kept.
  std::int64_t unstable_sensitivity_samples() const { return unstable_; }

 private:
  void Recentre();

  ThreeStepOptions options_;
  int order_;
  Rls<kSensitivityParams> ls_;
  IvRls<kSensitivityParams> iv_;
  Rls<kParams> fit_;
  bool frozen_ = false;
  SensitivityVector f_used_ = SensitivityVector::Zero();
  // Histories, index 0 = the current sample: u(i..i-m), t(i-1..i-m), t_hat and free responses.
  Eigen::Matrix<double, kMaxOrder + 1, 1> u_ = Eigen::Matrix<double, kMaxOrder + 1, 1>::Zero();
  Eigen::Matrix<double, kMaxOrder, 1> t_ = Eigen::Matrix<double, kMaxOrder, 1>::Zero();
  Eigen::Matrix<double, kMaxOrder, 1> t_hat_ = Eigen::Matrix<double, kMaxOrder, 1>::Zero();
  Eigen::Matrix<double, kMaxOrder, kMaxOrder> free_ =
      Eigen::Matrix<double, kMaxOrder, kMaxOrder>::Zero();  // column r: f_r history
  Eigen::Matrix<double, 1 + kMaxOrder, 1> integrated_ =
      Eigen::Matrix<double, 1 + kMaxOrder, 1>::Zero();  // Q_hat, F_1..F_4
  Eigen::Matrix<double, 1 + kMaxOrder, 1> centre_ = Eigen::Matrix<double, 1 + kMaxOrder, 1>::Zero();
  double t_centre_ = 0.0;
  std::int64_t i_ = -1;
  std::int64_t unstable_ = 0;
};

/// true when 1 + a_1 z^-1 + ... + a_m z^-m has all its roots strictly inside the unit circle
/// (Schur-Cohn step-down on the reflection coefficients).  m <= 4.  Never allocates.
bool StableAutoregression(const Eigen::Ref<const Eigen::Matrix<double, 4, 1>>& a, int order);

}  // namespace canalid::core
