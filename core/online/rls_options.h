#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <limits>

namespace canalid::core {

/// The update law of an Rls estimator.  All share the guards of RlsOptions.  With forgetting 1 and
/// a large initial covariance every least-squares variant equals batch least squares.
enum class RlsMethod {
  /// Default.  Bierman's UD-factorised update, P = U D U' (U unit upper triangular, D > 0: P
  /// stays symmetric positive definite by construction) with Kulhavy's directional forgetting:
  /// P <- P - beta P phi phi' P / (lambda + r), beta = 1 - (1 - lambda) / r, which is Bierman's
  /// measurement update with the variance R = r / (r - (1 - lambda)); gain P phi / (lambda + r).
  /// When r <= 1 - lambda (phi already known better than the memory allows) beta is taken as 0:
  /// theta is updated, P is left alone.  Information is forgotten only in excited directions,
  /// so P stays bounded when excitation stops (no windup).
  kUdDirectional,
  /// Bierman's UD update with exponential forgetting (D divided by lambda).
  kUdExponential,
  /// Covariance form with exponential forgetting, P <- (P - P phi phi' P / (lambda + r)) / lambda,
  /// r = phi' P phi, symmetrised after each step.  Winds up when excitation stops.
  kExponential,
  /// Kulhavy's directional forgetting: information is forgotten only along phi,
  /// P <- P - beta P phi phi' P / (lambda + r), beta = 1 - (1 - lambda) / r (beta = 1 if
  /// r < excitation_min), gain P phi / (lambda + r).  P stays bounded without excitation.
  kDirectional,
  /// Constant trace: the no-forgetting update followed by scaling P to trace(P) = trace_max.
  kConstantTrace,
  /// Stabilised forgetting toward a prior covariance p_prior I (Kulhavy-Zarrop):
  /// P^-1 <- lambda P^-1 + (1 - lambda) / p_prior I + phi phi'.  Without excitation P tends to
  /// p_prior I instead of growing.  O(n^3) per update (a Cholesky solve).
  kStabilised,
  /// Kalman filter for random-walk parameters theta(k) = theta(k-1) + w, cov(w) = q I, unit
  /// measurement noise variance (P and q are relative to it):
  /// K = P phi / (1 + r), P <- P - K phi' P + q I.  Forgetting is ignored.
  kKalman,
  /// Normalised LMS: theta += mu phi e / (epsilon + phi' phi).  No covariance: the reported P
  /// stays p0 I and standard deviations are NaN.
  kNlms,
};

/// Whether an Rls with this method minimises a (weighted) least-squares cost, so that its
/// residual_sum_of_squares() is that cost's minimum: the exponential-forgetting forms exactly, the
/// directional ones exactly at lambda = 1 (for lambda < 1 they forget only along the excited
/// directions, which no single weighting of the rows describes; the loss is then the
/// exponentially weighted residual of a nearby fit).  Constant trace, stabilised, Kalman and NLMS
/// do not (P is held, regularised, inflated or absent), and BankCriterion::kResidual does not
/// apply to them.  The innovation guards (Huber, rejection, dead zone, CUSUM) and trace bounds,
/// off by default, also change the cost.
constexpr bool IsLeastSquaresMethod(RlsMethod method) {
  return method == RlsMethod::kUdDirectional || method == RlsMethod::kUdExponential ||
         method == RlsMethod::kExponential || method == RlsMethod::kDirectional;
}

/// Options of Rls.  Innovation guards use the normalised a-priori innovation
/// z = e / sqrt(sigma2 (1 + phi' P phi / lambda)), sigma2 the running innovation variance estimate;
/// they are active once the weighted sample count exceeds n + warmup_samples.
struct RlsOptions {
  RlsMethod method = RlsMethod::kUdDirectional;
  double forgetting = 1.0;                                     ///< lambda, 0 < lambda <= 1
  double initial_covariance = 1e6;                             ///< P0 = p0 I, > 0
  double trace_max = std::numeric_limits<double>::infinity();  ///< P scaled down above it
  double trace_min = 0.0;  ///< P scaled up below it (a floor against lock-up)
  double eigen_min = 0.0;  ///< covariance forms: P += delta I when the Gershgorin bound is lower
  double prior_covariance = 1.0;    ///< kStabilised: p_prior
  double process_noise = 0.0;       ///< kKalman: q (relative to the measurement noise variance)
  double nlms_step = 0.5;           ///< kNlms: mu, 0 < mu < 2
  double nlms_epsilon = 1e-9;       ///< kNlms: epsilon > 0
  double regressor_norm_min = 0.0;  ///< freeze when ||phi||^2 <= this
  double excitation_min = 0.0;      ///< freeze when phi' P phi <= this (covariance methods)
  double dead_zone = 0.0;           ///< no update when |z| < dead_zone
  double huber = std::numeric_limits<double>::infinity();   ///< clip |z| to huber
  double reject = std::numeric_limits<double>::infinity();  ///< reject the sample when |z| > it
  /// Two-sided CUSUM on z: g+ = max(0, g+ + z - drift), g- = max(0, g- - z - drift); when either
  /// exceeds cusum_threshold the covariance is reset to p0 I (theta kept) and g is cleared.
  double cusum_drift = 0.5;
  double cusum_threshold = std::numeric_limits<double>::infinity();
  double noise_forgetting = 0.0;    ///< for sigma2; 0 = lambda (1 for Kalman and NLMS)
  int warmup_samples = 10;          ///< >= 0
  double regressor_abs_max = 1e12;  ///< |phi_i| above it: the sample is rejected as absurd
  double output_abs_max = 1e12;     ///< |y| above it: the sample is rejected as absurd
  Eigen::VectorXd lower;            ///< box projection of theta (empty = none); size n when given
  Eigen::VectorXd upper;            ///< box projection of theta (empty = none); size n when given

  /// @throws std::invalid_argument naming the first option out of range (n = parameter count).
  void Validate(int num_params) const;
};

/// What Update did with a sample.
enum class RlsOutcome {
  kUpdated,          ///< parameters and covariance updated
  kRejectedInvalid,  ///< non-finite or absurd regressor/output: nothing changed
  kRejectedOutlier,  ///< |z| > reject: nothing changed
  kDeadZone,         ///< |z| < dead_zone: only the noise estimate changed
  kFrozen,           ///< regressor without information: only the noise estimate changed
};

/// Numerical health after the last update (data, published with each model).
struct RlsHealth {
  double trace_p = 0.0;              ///< trace(P)
  double condition_estimate = 1.0;   ///< max/min diagonal of D (UD) or of P: a cheap proxy
  double excitation = 0.0;           ///< phi' P phi of the last valid sample
  double regressor_norm2 = 0.0;      ///< ||phi||^2 of the last valid sample
  double innovation_variance = 0.0;  ///< sigma2
  bool frozen = false;               ///< last sample carried no information
  bool wound_up = false;  ///< trace(P) at trace_max or above n p0 (only forgetting can do that)
  std::int64_t updates = 0;
  std::int64_t rejected_invalid = 0;
  std::int64_t rejected_outliers = 0;
  std::int64_t clipped = 0;  ///< Huber-clipped innovations
  std::int64_t dead_zone = 0;
  std::int64_t frozen_count = 0;
  std::int64_t projections = 0;    ///< samples after which theta was projected onto the box
  std::int64_t resets = 0;         ///< covariance resets by the change detector
  std::int64_t trace_bounded = 0;  ///< samples on which a trace or eigenvalue bound acted
};

}  // namespace canalid::core
