#pragma once
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/online/rls_options.h"

namespace canalid::core {

/// Recursive instrumental-variable least squares (Ljung & Soderstrom, "Theory and Practice of
/// Recursive Identification", section 3.6) for y(k) = phi(k)' theta + v(k) when phi is correlated
/// with v (closed loop) but an instrument z(k) is not, while being correlated with phi:
///   e = y - phi' theta,  r = phi' P z,  K = P z / (lambda + r),
///   theta += K e,        P <- (P - K phi' P) / lambda,
///   R <- lambda R + z z'  (the instruments' moment matrix, for the covariance).
/// With lambda = 1 and P0 = p0 I, P(k) = (sum z phi' + I / p0)^-1 and theta(k) is the batch IV
/// estimate (sum z phi')^-1 sum z y up to the prior's weight.  P is not symmetric and need not be
/// positive definite, so the factorised forms of Rls do not apply.
/// Covariance() gives the IV asymptotic covariance P R P' (relative to sigma2), sigma2 is
/// estimated from the a-posteriori residuals: V <- nu V + (y - phi' theta_new)^2, m <- nu m + 1,
/// sigma2 = V / max(m - n, 1).
/// Uses from RlsOptions: forgetting, initial_covariance, noise_forgetting, excitation_min (frozen
/// when |r| <= it or |lambda + r| <= 1e-12 lambda), regressor_abs_max and output_abs_max (a
/// non-finite or absurd phi, z or y is rejected: nothing changes), trace_max (P scaled down when
/// |trace P| exceeds it), lower/upper (theta projected onto the box).  The method, the innovation
/// guards and the other bounds are ignored (the Validate() rules still apply).
/// Forgetting is exponential: when excitation stops P grows like lambda^-k (windup), bounded only
/// by trace_max; with lambda < 1 on a record with long quiet spells, set trace_max.
/// N is the parameter count (fixed size).  Everything is allocated in the constructor; Update never
/// allocates.  Deterministic.  Pure, not thread-safe.
template <int N>
class IvRls final {
  static_assert(N > 0, "IvRls needs a fixed size");

 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  struct Result {
    double prediction_error;  ///< a-priori e (NaN when rejected as invalid)
    RlsOutcome outcome;
  };

  /// @throws std::invalid_argument on a bad option (RlsOptions::Validate with n = N).
  explicit IvRls(const RlsOptions& options) : options_(options) {
    options_.Validate(N);
    has_box_ = options_.lower.size() == N && options_.upper.size() == N;
    lower_ = has_box_ ? Vector(options_.lower) : Vector::Zero();
    upper_ = has_box_ ? Vector(options_.upper) : Vector::Zero();
    nu_ = options_.noise_forgetting > 0.0 ? options_.noise_forgetting : options_.forgetting;
    Reset();
  }

  /// theta = 0, P = p0 I, R = 0; clears the noise estimate and the health counts.
  void Reset() {
    theta_.setZero();
    p_ = Matrix::Identity() * options_.initial_covariance;
    r_zz_.setZero();
    ssr_ = 0.0;
    weight_ = 0.0;
    last_error_ = std::numeric_limits<double>::quiet_NaN();
    health_ = RlsHealth{};
  }

  /// One sample.  Never throws, never allocates.
  template <typename D1, typename D2>
  Result Update(const Eigen::MatrixBase<D1>& phi, const Eigen::MatrixBase<D2>& z, double y) {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    bool ok = std::isfinite(y) && std::abs(y) <= options_.output_abs_max;
    double norm2 = 0.0;
    for (int i = 0; ok && i < N; ++i) {
      ok = std::isfinite(phi(i)) && std::isfinite(z(i)) &&
           std::abs(phi(i)) <= options_.regressor_abs_max &&
           std::abs(z(i)) <= options_.regressor_abs_max;
      norm2 += phi(i) * phi(i);
    }
    if (!ok) {
      ++health_.rejected_invalid;
      return {kNaN, RlsOutcome::kRejectedInvalid};
    }
    const double lambda = options_.forgetting;
    const double e = y - phi.dot(theta_);
    pz_.noalias() = p_ * z;
    const double r = phi.dot(pz_);
    if (!std::isfinite(e) || !std::isfinite(r)) {
      ++health_.rejected_invalid;
      return {kNaN, RlsOutcome::kRejectedInvalid};
    }
    last_error_ = e;
    health_.excitation = r;
    health_.regressor_norm2 = norm2;
    const double den = lambda + r;
    health_.frozen = std::abs(r) <= options_.excitation_min || std::abs(den) <= 1e-12 * lambda;
    if (health_.frozen) {
      ++health_.frozen_count;
      return {e, RlsOutcome::kFrozen};
    }
    theta_ += pz_ * (e / den);
    ptphi_.noalias() = p_.transpose() * phi;
    p_.noalias() -= (1.0 / den) * pz_ * ptphi_.transpose();
    if (lambda != 1.0) {
      p_ /= lambda;
      r_zz_ *= lambda;
    }
    r_zz_.noalias() += z * z.transpose();
    bounded_ = false;
    const double t = std::abs(p_.trace());
    if (t > options_.trace_max) {
      p_ *= options_.trace_max / t;
      bounded_ = true;
      ++health_.trace_bounded;
    }
    if (has_box_) {
      const Vector projected = theta_.cwiseMax(lower_).cwiseMin(upper_);
      if (projected != theta_) {
        theta_ = projected;
        ++health_.projections;
      }
    }
    const double post = y - phi.dot(theta_);
    ssr_ = nu_ * ssr_ + post * post;
    weight_ = nu_ * weight_ + 1.0;
    health_.innovation_variance = ssr_ / std::max(weight_ - N, 1.0);
    ++health_.updates;
    return {e, RlsOutcome::kUpdated};
  }

  /// Re-parameterises theta' = T theta for phi' = T^-T phi and z' = S^-T z (e.g. re-centred
  /// regressor and instrument): P' = T P S', R' = S^-T R S^-1.  O(n^3).
  /// @pre S invertible.
  void Transform(const Matrix& t, const Matrix& s) {
    w_.noalias() = t * p_;
    p_.noalias() = w_ * s.transpose();
    const Matrix s_inverse = s.inverse();  // fixed size: closed form, no allocation
    w_.noalias() = s_inverse.transpose() * r_zz_;
    r_zz_.noalias() = w_ * s_inverse;
    pz_.noalias() = t * theta_;
    theta_ = pz_;
  }

  static constexpr int num_params() { return N; }
  const Vector& theta() const { return theta_; }
  /// The gain matrix P = (sum lambda^(k-j) z phi' + ...)^-1.
  const Matrix& gain_matrix() const { return p_; }
  /// The IV covariance relative to sigma2: P R P'.  O(n^3).
  void Covariance(Matrix& out) const { out.noalias() = p_ * r_zz_ * p_.transpose(); }
  /// sqrt(sigma2 (P R P')_ii).
  double StandardDeviation(int i) const {
    const double v = (p_.row(i) * r_zz_).dot(p_.row(i));
    return std::sqrt(std::max(0.0, health_.innovation_variance * v));
  }
  double innovation_variance() const { return health_.innovation_variance; }
  double last_prediction_error() const { return last_error_; }
  /// trace_p = trace(P); condition_estimate = max/min |P_ii|; wound_up when |trace P| reached
  /// trace_max or exceeds n p0.
  RlsHealth health() const {
    RlsHealth h = health_;
    h.trace_p = p_.trace();
    const Vector d = p_.diagonal().cwiseAbs();
    h.condition_estimate =
        d.minCoeff() > 0.0 ? d.maxCoeff() / d.minCoeff() : std::numeric_limits<double>::infinity();
    const double t = std::abs(h.trace_p);
    h.wound_up = (bounded_ && t >= options_.trace_max * (1.0 - 1e-12)) ||
                 t > N * options_.initial_covariance * (1.0 + 1e-9);
    return h;
  }
  const RlsOptions& options() const { return options_; }

 private:
  RlsOptions options_;
  bool has_box_ = false;
  Vector lower_;
  Vector upper_;
  Vector theta_;
  Vector pz_;     // work: P z
  Vector ptphi_;  // work: P' phi
  Matrix p_;
  Matrix r_zz_;
  Matrix w_;  // work
  double nu_ = 1.0;
  double ssr_ = 0.0;
  double weight_ = 0.0;
  double last_error_ = std::numeric_limits<double>::quiet_NaN();
  bool bounded_ = false;
  RlsHealth health_;
};

}  // namespace canalid::core
