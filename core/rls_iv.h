#pragma once
#include <Eigen/Core>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/rls_options.h"

namespace canalid::core {

/// Recursive instrumental-variable least squares for y(k) = phi(k)' theta + v(k) when phi is
/// correlated with v but an instrument z(k) is not:
///   e = y - phi' theta,  K = P z / (lambda + phi' P z),  theta += K e,  P <- (P - K phi' P) /
///   lambda,
/// so that with lambda = 1, P = (sum z phi' + I / p0)^-1 and theta is the batch IV estimate
/// (sum z phi')^-1 sum z y up to the prior.  P is not symmetric.  Uses from RlsOptions:
/// forgetting, initial_covariance, trace_max (|trace P| scaled down above it), excitation_min
/// (freeze when |phi' P z| <= it), regressor_abs_max, output_abs_max, noise_forgetting, lower,
/// upper; the method and the innovation guards are ignored.  Standard deviations are
/// sqrt(sigma2 |P_ii|): a scale, not the IV asymptotic covariance.
/// Allocates only in the constructor.  Deterministic.  Pure, not thread-safe.
template <int N>
class IvRls final {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  struct Result {
    double prediction_error;
    RlsOutcome outcome;
  };

  /// @throws std::invalid_argument on a bad option or size.
  explicit IvRls(const RlsOptions& options, int num_params = N)
      : options_(options), n_(num_params) {
    if (N != Eigen::Dynamic && num_params != N) {
      throw std::invalid_argument("IvRls: num_params = " + std::to_string(num_params) +
                                  " must equal the template size " + std::to_string(N));
    }
    options_.Validate(num_params);
    theta_.setZero(n_);
    pz_.setZero(n_);
    ptphi_.setZero(n_);
    w_.setZero(n_, n_);
    w2_.setZero(n_, n_);
    p_.setIdentity(n_, n_);
    p_ *= options_.initial_covariance;
    lambda_ = options_.forgetting;
    nu_ = options_.noise_forgetting > 0.0 ? options_.noise_forgetting : lambda_;
  }

  /// @pre phi.size() == z.size() == num_params().  Never throws or allocates.
  template <typename D1, typename D2>
  Result Update(const Eigen::MatrixBase<D1>& phi, const Eigen::MatrixBase<D2>& z, double y) {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    bool ok = std::isfinite(y) && std::abs(y) <= options_.output_abs_max;
    for (int i = 0; ok && i < n_; ++i) {
      ok = std::isfinite(phi(i)) && std::isfinite(z(i)) &&
           std::abs(phi(i)) <= options_.regressor_abs_max &&
           std::abs(z(i)) <= options_.regressor_abs_max;
    }
    if (!ok) {
      ++health_.rejected_invalid;
      return {kNaN, RlsOutcome::kRejectedInvalid};
    }
    const double e = y - phi.dot(theta_);
    pz_.noalias() = p_ * z;
    const double r = phi.dot(pz_);
    last_error_ = e;
    health_.excitation = r;
    if (!std::isfinite(r) || std::abs(r) <= options_.excitation_min || lambda_ + r == 0.0) {
      ++health_.frozen_count;
      return {e, RlsOutcome::kFrozen};
    }
    const double den = lambda_ + r;
    theta_ += pz_ * (e / den);
    ptphi_.noalias() = p_.transpose() * phi;
    p_.noalias() -= (1.0 / den) * pz_ * ptphi_.transpose();
    if (lambda_ != 1.0) p_ /= lambda_;
    const double t = std::abs(p_.trace());
    if (t > options_.trace_max) {
      p_ *= options_.trace_max / t;
      ++health_.trace_bounded;
    }
    if (options_.lower.size() == n_ && options_.upper.size() == n_) {
      for (int i = 0; i < n_; ++i) {
        const double v = std::min(std::max(theta_(i), options_.lower(i)), options_.upper(i));
        if (v != theta_(i)) {
          theta_(i) = v;
          ++health_.projections;
        }
      }
    }
    // Residual variance from the a-posteriori error (the IV analogue of SSR / (N - n)).
    const double post = y - phi.dot(theta_);
    ssr_ = nu_ * ssr_ + post * post;
    weight_ = nu_ * weight_ + 1.0;
    health_.innovation_variance = ssr_ / std::max(weight_ - n_, 1.0);
    ++health_.updates;
    return {e, RlsOutcome::kUpdated};
  }

  /// theta' = T theta with instrument re-parameterisation S: when phi' = T^-T phi and
  /// z' = S^-T z, P' = T P S'.  O(n^3).
  void Transform(const Matrix& t, const Matrix& s) {
    w_.noalias() = t * p_;
    w2_.noalias() = w_ * s.transpose();
    p_ = w2_;
    pz_.noalias() = t * theta_;
    theta_ = pz_;
  }

  int num_params() const { return n_; }
  const Vector& theta() const { return theta_; }
  void Covariance(Matrix& out) const { out = p_; }
  double StandardDeviation(int i) const {
    return std::sqrt(std::abs(health_.innovation_variance * p_(i, i)));
  }
  double innovation_variance() const { return health_.innovation_variance; }
  double last_prediction_error() const { return last_error_; }
  RlsHealth health() const {
    RlsHealth h = health_;
    h.trace_p = p_.trace();
    return h;
  }

 private:
  RlsOptions options_;
  int n_;
  Vector theta_;
  Vector pz_;
  Vector ptphi_;
  Matrix p_;
  Matrix w_;
  Matrix w2_;
  double lambda_ = 1.0;
  double nu_ = 1.0;
  double ssr_ = 0.0;
  double weight_ = 0.0;
  double last_error_ = std::numeric_limits<double>::quiet_NaN();
  RlsHealth health_;
};

}  // namespace canalid::core
