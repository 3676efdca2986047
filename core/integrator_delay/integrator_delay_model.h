#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/numerics/metrics.h"

namespace canalid::core {

/// Integrator-Delay model of a canal pool, sampled with period Ts (docs/references.md):
///   y(k) - y(k-1) = b (q_in(k - nk) - q_out(k - 1)),   b = Ts / A,   tau = nk Ts.
struct IntegratorDelayModel {
  double b = 0.0;              ///< backwater coefficient, s/m^2
  int nk = 0;                  ///< delay in samples
  double sample_time_s = 1.0;  ///< Ts
  double delay_s() const { return nk * sample_time_s; }
  double area_m2() const { return sample_time_s / b; }
};

/// kThreeStep: the batch FitIntegratorDelay treats it as kOn (its closed-loop method is the
/// three-step one); OnlineIntegratorDelayBank runs OnlineThreeStep instead of its
/// instrumental-variable bank.
enum class ClosedLoopMode { kAuto, kOn, kOff, kThreeStep };

struct IntegratorDelayFitOptions {
  int min_nk = 0;
  int max_nk = -1;  ///< < 0: a third of the record
  ClosedLoopMode closed_loop = ClosedLoopMode::kAuto;
};

/// What FitIntegratorDelay found, with the evidence for it.
struct IntegratorDelayFit {
  IntegratorDelayModel model;
  double wave_front_gain_s_per_m2 = 0.0;  ///< p21 in y = b Q + p21 q_in(k-nk) + c + d (k-k0)
  double offset_m = 0.0;                  ///< c
  double drift_m_per_sample = 0.0;        ///< d (sensor drift and flow-meter bias end up here)
  int first_sample = 0;                   ///< k0: samples before it only feed the delayed inflow
  bool closed_loop = false;               ///< true: the three-step closed-loop method was used
  std::string closed_loop_reason;         ///< why (option, or the correlation found by kAuto)
  double outflow_level_correlation = 0.0;
  Eigen::VectorXd loss_by_nk;      ///< mean squared residual of the scan, index nk - min_nk
  double open_loop_area_m2 = 0.0;  ///< the plain fit at the chosen nk
  double iv_area_m2 = 0.0;         ///< instrumental-variable cross-check (instrument: inflow)
  /// Closed loop: the sensitivity model of step (2), order m (1..4, 0 when not fitted) and
  /// theta = [a_1..a_m, b_0..b_{m-1}] of t(k) = -sum a_i t(k-i) + sum b_j (u(k-j) - u(k-m)),
  /// u the detrended delayed inflow and t the detrended total flow over samples k0..N-1.
  int sensitivity_order = 0;
  Eigen::VectorXd sensitivity_theta;
  FitMetrics metrics;               ///< simulated level against measured, samples k0..N-1
  Eigen::VectorXd simulated_level;  ///< samples k0..N-1
  std::vector<std::string> warnings;
};

/// Fits the ID model on the level against the integrated total flow, not on one-step
/// differences (those weight the wave front and underestimate A, a known pitfall).
/// For each candidate nk in [min_nk, max_nk], with k0 = max_nk + 1 so every candidate uses the
/// same samples:
///   v(k) = q_in(k - nk) - q_out(k - 1),   Q(k) = sum_{j=k0..k} v(j),
///   y(k) = b Q(k) + p21 q_in(k - nk) + c + d (k - k0)
/// by least squares (QR), and nk minimises the residual.  p21 is IDZ's direct gain of the inflow
/// (the wave front arrives as a jump); c and d take the offset and a linear drift of the sensor.
/// With a fixed downstream gate the outflow follows the level (closed loop) and measured total flow
/// is correlated with the noise; then the three-step method of Van den Hof & Schrama is used: (1)
/// nk from the scan, (2) a 4th-order ARX from the delayed inflow to the total flow constrained to
/// zero DC gain, (3) the noise-free total flow simulated through it, integrated and fitted as
/// above.  kAuto decides from the data: closed loop when the outflow moves (std above 2 % of the
/// inflow's) and correlates with the level
/// (r > 0.3, both detrended: a level-driven outflow rises with the level, while one moved on
/// its own lowers the level it drains, r < 0).  The instrumental variable with the integrated
/// delayed inflow as instrument is always computed as a cross-check.
/// @throws std::invalid_argument on size mismatch, non-finite data, Ts <= 0, fewer than 20
///         samples after k0, or an inflow that never moves.
IntegratorDelayFit FitIntegratorDelay(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                      const Eigen::Ref<const Eigen::VectorXd>& q_out,
                                      const Eigen::Ref<const Eigen::VectorXd>& level,
                                      double sample_time_s,
                                      const IntegratorDelayFitOptions& options = {});

/// Checks a pool record: equal lengths, Ts > 0, finite values, an inflow that moves.
/// @throws std::invalid_argument with the message prefixed by `what`.
void ValidatePoolRecord(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                        const Eigen::Ref<const Eigen::VectorXd>& q_out,
                        const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
                        const std::string& what);

/// Rows k = k0..N-1 of the open-loop regression [Q(k), q_in(k - nk), 1, k - k0] (see
/// FitIntegratorDelay).
Eigen::MatrixXd OpenLoopRegressors(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                   const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk, int k0);

/// The integrated total flow Q(k) for k = k0..N-1 (see FitIntegratorDelay).
Eigen::VectorXd IntegratedTotalFlow(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                    const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk, int k0);

}  // namespace canalid::core
