#pragma once
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/online/rls_options.h"

namespace canalid::core {

/// Recursive least squares for y(k) = phi(k)' theta + e(k), n parameters, with the update laws
/// of RlsMethod and the guards of RlsOptions.  Per sample, in this order:
///  1. a non-finite or absurd sample (|phi_i| > regressor_abs_max, |y| > output_abs_max) is
///     rejected and counted; nothing else changes;
///  2. a-priori error e = y - phi' theta, r = phi' P phi, normalised innovation
///     z = e / sqrt(sigma2 (1 + r / lambda)) (after the warm-up);
///  3. |z| > reject: rejected as an outlier; |z| > huber: e clipped to huber sigma sqrt(...);
///     CUSUM on the (clipped) z resets P to p0 I on a detected change; |z| < dead_zone: no update;
///  4. ||phi||^2 <= regressor_norm_min or r <= excitation_min: frozen (no update, no forgetting);
///  5. the update law; theta projected onto [lower, upper]; trace(P) kept in [trace_min,
///     trace_max] by scaling P; covariance forms also get the eigenvalue floor eigen_min;
///  6. the innovation variance: V <- nu V + e^2 / (1 + r / lambda), m <- nu m + 1,
///     sigma2 = V / max(m - n, 1).  With lambda = nu = 1 this is exactly the batch residual
///     variance SSR / (N - n), and the standard deviations sqrt(sigma2 diag P) are the batch ones.
/// N is the parameter count (fixed-size Eigen) or Eigen::Dynamic (the size is given at
/// construction).  Everything is allocated in the constructor; Update never allocates.
/// Deterministic: the same samples give bit-identical results.  Pure, not thread-safe.
template <int N>
class Rls final {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;

  struct Result {
    double prediction_error;  ///< a-priori e = y - phi' theta (NaN when rejected as invalid)
    RlsOutcome outcome;
  };

  /// @param num_params n; must equal N unless N is Eigen::Dynamic (then n >= 1).
  /// @throws std::invalid_argument on a bad option (RlsOptions::Validate) or size.
  explicit Rls(const RlsOptions& options, int num_params = N);

  /// One sample.  @pre phi.size() == num_params().  Never throws, never allocates.
  template <typename Derived>
  Result Update(const Eigen::MatrixBase<Derived>& phi, double y);

  /// phi' theta.
  template <typename Derived>
  double Predict(const Eigen::MatrixBase<Derived>& phi) const {
    return phi.dot(theta_);
  }

  /// Restarts from theta0 (default zero) and P0 = p0 I; clears noise estimate and health counts.
  void Reset();
  /// P <- p0 I, theta kept (what the change detector does).
  void ResetCovariance();
  /// Sets theta (e.g. a prior).  @pre theta.size() == num_params().
  void SetTheta(const Vector& theta) { theta_ = theta; }
  /// Sets P (symmetric positive definite; refactorised for the UD method).
  void SetCovariance(const Matrix& p);
  /// Re-parameterises theta' = T theta, P' = T P T' (e.g. re-centring a regressor so that
  /// phi' = T^-T phi stays bounded).  O(n^3); allocates for Eigen::Dynamic.
  void Transform(const Matrix& t);

  int num_params() const { return n_; }
  const Vector& theta() const { return theta_; }
  /// Full P (O(n^3) for the UD form).
  void Covariance(Matrix& out) const;
  /// sqrt(sigma2 P_ii); NaN for NLMS.
  void StandardDeviations(Vector& out) const;
  /// sqrt(sigma2 P_ii) of one parameter (O(n)); NaN for NLMS.  @pre 0 <= i < num_params().
  double StandardDeviation(int i) const;
  /// P_ii, relative to sigma2 (O(n) for the UD form); NaN for NLMS.  @pre 0 <= i < n.
  double CovarianceDiagonal(int i) const;
  /// sigma2, the innovation variance estimate.
  double innovation_variance() const { return health_.innovation_variance; }
  /// V of step 6, the weighted sum of the squared normalised innovations: with lambda = nu = 1
  /// and a large P0, the batch least-squares residual sum of squares of the samples given.
  double residual_sum_of_squares() const { return ssr_; }
  double last_prediction_error() const { return last_error_; }
  /// Counters and flags of the last update; trace(P) and the condition estimate are computed
  /// here (O(n^2), no allocation) so that Update does not pay for them.
  RlsHealth health() const;
  const RlsOptions& options() const { return options_; }
  /// Exact condition number of P by an eigen decomposition; O(n^3); not for the sample path.
  double ConditionNumber() const;

 private:
  bool UsesUd() const {
    return options_.method == RlsMethod::kUdDirectional ||
           options_.method == RlsMethod::kUdExponential;
  }
  bool UsesCovariance() const { return !UsesUd() && options_.method != RlsMethod::kNlms; }
  double GainForgetting() const {
    return (options_.method == RlsMethod::kKalman || options_.method == RlsMethod::kNlms ||
            options_.method == RlsMethod::kConstantTrace)
               ? 1.0
               : options_.forgetting;
  }
  template <typename Derived>
  double Excitation(const Eigen::MatrixBase<Derived>& phi);
  void UpdateUdFactors(double measurement_variance);
  /// num_params after checking it and the options, before any member is sized by it (Eigen
  /// asserts on a fixed size given another, or a negative one).
  static int CheckedSize(const RlsOptions& options, int num_params);
  void UpdateNoise(double e, double scale);
  void Symmetrise();
  double Trace() const;
  void ScaleP(double factor);
  void BoundCovariance();
  void Project();

  template <int M>
  friend class RlsBank;  // copies a lane's state in and out (RlsBank::Lane, Transform)

  RlsOptions options_;
  int n_;
  Vector theta_;
  Vector lower_;
  Vector upper_;
  bool has_box_ = false;
  Matrix u_;             // UD: unit upper triangular U
  Vector d_;             // UD: diagonal D
  Matrix p_;             // covariance forms: P
  Vector f_;             // work: U' phi (UD)
  Vector g_;             // work: D f (UD) or P phi
  Vector k_;             // work: gain accumulator, P phi
  Vector alpha_;         // work: Bierman partial sums
  Vector inv_alpha_;     // work: their inverses
  bool guards_ = false;  // any innovation guard configured
  Matrix w_;             // work matrices (stabilised, transform)
  Matrix w2_;
  Eigen::LLT<Matrix> llt_;
  Eigen::SelfAdjointEigenSolver<Matrix> eig_;
  double noise_forgetting_ = 1.0;
  double ssr_ = 0.0;     // weighted sum of normalised squared innovations
  double weight_ = 0.0;  // weighted sample count
  long long accepted_ = 0;
  double cusum_pos_ = 0.0;
  double cusum_neg_ = 0.0;
  double last_error_ = std::numeric_limits<double>::quiet_NaN();
  bool bounded_ = false;
  RlsHealth health_;
};

// ---------------------------------------------------------------------------------------------
// Implementation (a template on N, so it lives in the header).

template <int N>
int Rls<N>::CheckedSize(const RlsOptions& options, int num_params) {
  if (N != Eigen::Dynamic && num_params != N) {
    throw std::invalid_argument("Rls: num_params = " + std::to_string(num_params) +
                                " must equal the template size " + std::to_string(N));
  }
  options.Validate(num_params);
  return num_params;
}

template <int N>
Rls<N>::Rls(const RlsOptions& options, int num_params)
    : options_(options), n_(CheckedSize(options, num_params)), llt_(n_), eig_(n_) {
  theta_.setZero(n_);
  lower_.setConstant(n_, -std::numeric_limits<double>::infinity());
  upper_.setConstant(n_, std::numeric_limits<double>::infinity());
  if (options_.lower.size() == n_) {
    lower_ = options_.lower;
    has_box_ = true;
  }
  if (options_.upper.size() == n_) {
    upper_ = options_.upper;
    has_box_ = true;
  }
  u_.setIdentity(n_, n_);
  // Eigen 3.4's decompositions leave their status uninitialized until a first compute(), and
  // moving an Rls (a vector of them growing) copies it: an invalid enum value (UBSan). Compute
  // once here, on the identity, so every copy is of a defined state.
  llt_.compute(u_);
  eig_.compute(u_, Eigen::EigenvaluesOnly);
  d_.setZero(n_);
  p_.setZero(n_, n_);
  f_.setZero(n_);
  g_.setZero(n_);
  k_.setZero(n_);
  alpha_.setZero(n_);
  inv_alpha_.setZero(n_);
  guards_ = std::isfinite(options_.reject) || std::isfinite(options_.huber) ||
            options_.dead_zone > 0.0 || std::isfinite(options_.cusum_threshold);
  w_.setZero(n_, n_);
  w2_.setZero(n_, n_);
  if (options_.noise_forgetting > 0.0) {
    noise_forgetting_ = options_.noise_forgetting;
  } else {
    noise_forgetting_ =
        (options_.method == RlsMethod::kKalman || options_.method == RlsMethod::kNlms)
            ? 1.0
            : options_.forgetting;
  }
  Reset();
}

template <int N>
void Rls<N>::Reset() {
  theta_.setZero();
  ResetCovariance();
  ssr_ = 0.0;
  weight_ = 0.0;
  accepted_ = 0;
  last_error_ = std::numeric_limits<double>::quiet_NaN();
  health_ = RlsHealth{};
}

template <int N>
void Rls<N>::ResetCovariance() {
  u_.setIdentity();
  d_.setConstant(options_.initial_covariance);
  p_.setIdentity();
  p_ *= options_.initial_covariance;
  cusum_pos_ = 0.0;
  cusum_neg_ = 0.0;
}

template <int N>
void Rls<N>::SetCovariance(const Matrix& p) {
  p_ = p;
  Symmetrise();
  if (!UsesUd()) return;
  // UD factorisation from the last column backwards: P_ij = sum_{k >= j} U_ik d_k U_jk (i <= j).
  u_.setIdentity();
  for (int j = n_ - 1; j >= 0; --j) {
    double dj = p_(j, j);
    for (int k = j + 1; k < n_; ++k) dj -= d_(k) * u_(j, k) * u_(j, k);
    d_(j) = dj;
    for (int i = 0; i < j; ++i) {
      double uij = p_(i, j);
      for (int k = j + 1; k < n_; ++k) uij -= d_(k) * u_(i, k) * u_(j, k);
      u_(i, j) = uij / dj;
    }
  }
}

template <int N>
void Rls<N>::Covariance(Matrix& out) const {
  if (!UsesUd()) {
    out = p_;
    return;
  }
  for (int i = 0; i < n_; ++i) {
    for (int j = i; j < n_; ++j) {
      double s = 0.0;
      for (int k = j; k < n_; ++k) s += u_(i, k) * d_(k) * u_(j, k);
      out(i, j) = s;
      out(j, i) = s;
    }
  }
}

template <int N>
void Rls<N>::Transform(const Matrix& t) {
  Covariance(w_);
  w2_.noalias() = t * w_;
  w_.noalias() = w2_ * t.transpose();
  SetCovariance(w_);
  k_.noalias() = t * theta_;
  theta_ = k_;
}

template <int N>
double Rls<N>::StandardDeviation(int i) const {
  if (options_.method == RlsMethod::kNlms) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(std::max(0.0, health_.innovation_variance * CovarianceDiagonal(i)));
}

template <int N>
double Rls<N>::CovarianceDiagonal(int i) const {
  if (options_.method == RlsMethod::kNlms) return std::numeric_limits<double>::quiet_NaN();
  double pii = 0.0;
  // clang-tidy 14 compares the branches of a template's instantiation and calls them identical
  // (they are not: UD factors vs P); the false positive is reported only there.
  // NOLINTNEXTLINE(bugprone-branch-clone)
  if (UsesUd()) {
    for (int j = i; j < n_; ++j) pii += u_(i, j) * u_(i, j) * d_(j);
  } else {
    pii = p_(i, i);
  }
  return pii;
}

template <int N>
void Rls<N>::StandardDeviations(Vector& out) const {
  out.resize(n_);
  for (int i = 0; i < n_; ++i) out(i) = StandardDeviation(i);
}

template <int N>
double Rls<N>::ConditionNumber() const {
  Matrix p(n_, n_);
  Covariance(p);
  Eigen::SelfAdjointEigenSolver<Matrix> eig(p, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()(0);
  const double hi = eig.eigenvalues()(n_ - 1);
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

template <int N>
template <typename Derived>
double Rls<N>::Excitation(const Eigen::MatrixBase<Derived>& phi) {
  if (UsesUd()) {
    double r = 0.0;
    for (int j = 0; j < n_; ++j) {
      double fj = phi(j);
      for (int i = 0; i < j; ++i) fj += u_(i, j) * phi(i);
      f_(j) = fj;
      g_(j) = d_(j) * fj;
      r += fj * g_(j);
    }
    return r;
  }
  if (options_.method == RlsMethod::kNlms) return phi.squaredNorm();
  g_.noalias() = p_ * phi;
  return phi.dot(g_);
}

template <int N>
void Rls<N>::UpdateUdFactors(double measurement_variance) {
  // Bierman's measurement update of U and D with f_ = U' phi and g_ = D f (from Excitation):
  // P <- P - P phi phi' P / (R + r).  k_ accumulates P phi for the gain P phi / (R + r).
  // The partial sums alpha_j = R + sum_{i<=j} f_i g_i and their inverses are formed first, so
  // that the divisions do not sit on the dependency chain of the main loop.
  double alpha = measurement_variance;
  for (int j = 0; j < n_; ++j) {
    alpha += f_(j) * g_(j);
    alpha_(j) = alpha;
  }
  inv_alpha_ = alpha_.cwiseInverse();
  double alpha_prev = measurement_variance;
  double inv_prev = 1.0 / measurement_variance;
  for (int j = 0; j < n_; ++j) {
    d_(j) *= alpha_prev * inv_alpha_(j);
    const double pj = -f_(j) * inv_prev;
    const double gj = g_(j);
    for (int i = 0; i < j; ++i) {
      const double uij = u_(i, j);
      u_(i, j) = uij + k_(i) * pj;
      k_(i) += uij * gj;
    }
    k_(j) = gj;
    alpha_prev = alpha_(j);
    inv_prev = inv_alpha_(j);
  }
}

template <int N>
template <typename Derived>
typename Rls<N>::Result Rls<N>::Update(const Eigen::MatrixBase<Derived>& phi, double y) {
  assert(phi.size() == n_);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(y) || std::abs(y) > options_.output_abs_max) {
    ++health_.rejected_invalid;
    return {kNaN, RlsOutcome::kRejectedInvalid};
  }
  double norm2 = 0.0;
  for (int i = 0; i < n_; ++i) {
    const double v = phi(i);
    if (!std::isfinite(v) || std::abs(v) > options_.regressor_abs_max) {
      ++health_.rejected_invalid;
      return {kNaN, RlsOutcome::kRejectedInvalid};
    }
    norm2 += v * v;
  }
  // In index order (not Eigen's packet order), so that RlsBank's lanes compute the same sums.
  double prediction = 0.0;
  for (int i = 0; i < n_; ++i) prediction += phi(i) * theta_(i);
  const double e = y - prediction;
  double r = Excitation(phi);
  if (!std::isfinite(e) || !std::isfinite(r) || r < 0.0) {
    ++health_.rejected_invalid;
    return {kNaN, RlsOutcome::kRejectedInvalid};
  }
  last_error_ = e;
  health_.excitation = r;
  health_.regressor_norm2 = norm2;
  health_.frozen = false;
  const double lambda = GainForgetting();
  const bool has_p = options_.method != RlsMethod::kNlms;
  // Variance of the a-priori error in units of sigma2 (P is relative to sigma2).
  const double scale = has_p ? 1.0 + r / lambda : 1.0;
  double e_used = e;
  const double s2 = health_.innovation_variance;
  if (guards_ && accepted_ > n_ + options_.warmup_samples && s2 > 0.0) {
    const double sd = std::sqrt(s2 * scale);
    double z = e / sd;
    if (std::abs(z) > options_.reject) {
      ++health_.rejected_outliers;
      return {e, RlsOutcome::kRejectedOutlier};
    }
    if (std::abs(z) > options_.huber) {
      z = std::copysign(options_.huber, z);
      e_used = z * sd;
      ++health_.clipped;
    }
    cusum_pos_ = std::max(0.0, cusum_pos_ + z - options_.cusum_drift);
    cusum_neg_ = std::max(0.0, cusum_neg_ - z - options_.cusum_drift);
    if (cusum_pos_ > options_.cusum_threshold || cusum_neg_ > options_.cusum_threshold) {
      ResetCovariance();
      ++health_.resets;
      r = Excitation(phi);
    }
    if (std::abs(z) < options_.dead_zone) {
      ++accepted_;
      ++health_.dead_zone;
      UpdateNoise(e_used, scale);
      return {e, RlsOutcome::kDeadZone};
    }
  }
  ++accepted_;
  if (norm2 <= options_.regressor_norm_min || (has_p && r <= options_.excitation_min)) {
    ++health_.frozen_count;
    UpdateNoise(e_used, scale);
    health_.frozen = true;
    return {e, RlsOutcome::kFrozen};
  }
  switch (options_.method) {
    case RlsMethod::kUdExponential: {
      // P <- (P - P phi phi' P / (lambda + r)) / lambda: Bierman with R = lambda, then D / lambda.
      UpdateUdFactors(lambda);
      theta_ += k_ * (e_used / (lambda + r));
      if (lambda != 1.0) d_ /= lambda;
      break;
    }
    case RlsMethod::kUdDirectional: {
      const double forget = 1.0 - lambda;
      if (r > forget) {
        // Bierman's accumulator ends as P_prior phi whatever R is, so it is the gain numerator.
        UpdateUdFactors(r / (r - forget));
      } else {
        for (int i = 0; i < n_; ++i) {
          double s = 0.0;
          for (int j = i; j < n_; ++j) s += u_(i, j) * g_(j);
          k_(i) = s;
        }
      }
      theta_ += k_ * (e_used / (lambda + r));
      break;
    }
    case RlsMethod::kExponential:
    case RlsMethod::kDirectional:
    case RlsMethod::kStabilised: {
      const double den = lambda + r;
      theta_ += g_ * (e_used / den);
      // Directional forgetting removes (1 - lambda) of the information along phi only.
      const double beta =
          options_.method == RlsMethod::kDirectional ? 1.0 - (1.0 - lambda) / r : 1.0;
      p_.noalias() -= (beta / den) * g_ * g_.transpose();
      if (options_.method == RlsMethod::kExponential) {
        // One division and n^2 multiplications instead of n^2 divisions (a tenth of the
        // update's time at n = 4, on CPUs where a division costs ten multiplications).
        p_ *= 1.0 / lambda;
      } else if (options_.method == RlsMethod::kStabilised) {
        // Here p_ = lambda (lambda R + phi phi')^-1; adding (1 - lambda)/p_prior I to the
        // information gives P (lambda I + c P)^-1 (P and the bracket commute).
        const double c = (1.0 - lambda) / options_.prior_covariance;
        w_ = c * p_;
        w_.diagonal().array() += lambda;
        llt_.compute(w_);
        w2_ = p_;
        llt_.solveInPlace(w2_);
        p_ = w2_;
      }
      Symmetrise();
      break;
    }
    case RlsMethod::kConstantTrace:
    case RlsMethod::kKalman: {
      const double den = 1.0 + r;
      theta_ += g_ * (e_used / den);
      p_.noalias() -= (1.0 / den) * g_ * g_.transpose();
      // NOLINTNEXTLINE(bugprone-branch-clone): as in StandardDeviation
      if (options_.method == RlsMethod::kKalman) {
        p_.diagonal().array() += options_.process_noise;
      } else {
        ScaleP(options_.trace_max / p_.trace());
      }
      Symmetrise();
      break;
    }
    case RlsMethod::kNlms:
      theta_ += phi * (options_.nlms_step * e_used / (options_.nlms_epsilon + norm2));
      break;
  }
  ++health_.updates;
  UpdateNoise(e_used, scale);
  Project();
  BoundCovariance();
  return {e, RlsOutcome::kUpdated};
}

template <int N>
void Rls<N>::UpdateNoise(double e, double scale) {
  ssr_ = noise_forgetting_ * ssr_ + e * e / scale;
  weight_ = noise_forgetting_ * weight_ + 1.0;
  health_.innovation_variance = ssr_ / std::max(weight_ - n_, 1.0);
}

template <int N>
void Rls<N>::Symmetrise() {
  for (int i = 0; i < n_; ++i) {
    for (int j = i + 1; j < n_; ++j) {
      const double s = 0.5 * (p_(i, j) + p_(j, i));
      p_(i, j) = s;
      p_(j, i) = s;
    }
  }
}

template <int N>
double Rls<N>::Trace() const {
  if (!UsesUd()) return p_.trace();
  double t = 0.0;
  for (int j = 0; j < n_; ++j) {
    double col = 1.0;
    for (int i = 0; i < j; ++i) col += u_(i, j) * u_(i, j);
    t += d_(j) * col;
  }
  return t;
}

template <int N>
void Rls<N>::ScaleP(double factor) {
  // NOLINTNEXTLINE(bugprone-branch-clone): as in StandardDeviation
  if (UsesUd()) {
    d_ *= factor;
  } else {
    p_ *= factor;
  }
}

template <int N>
void Rls<N>::BoundCovariance() {
  bounded_ = false;
  if (options_.method == RlsMethod::kNlms) return;
  const bool trace_bounds = std::isfinite(options_.trace_max) || options_.trace_min > 0.0;
  const double t = trace_bounds ? Trace() : 0.0;
  if (trace_bounds && t > options_.trace_max && options_.method != RlsMethod::kConstantTrace) {
    ScaleP(options_.trace_max / t);
    bounded_ = true;
  } else if (trace_bounds && t < options_.trace_min) {
    ScaleP(options_.trace_min / t);
    bounded_ = true;
  }
  if (options_.eigen_min > 0.0 && UsesCovariance()) {
    eig_.compute(p_, Eigen::EigenvaluesOnly);
    const double lo = eig_.eigenvalues()(0);
    if (lo < options_.eigen_min) {
      p_.diagonal().array() += options_.eigen_min - lo;
      bounded_ = true;
    }
  }
  if (bounded_) ++health_.trace_bounded;
}

template <int N>
void Rls<N>::Project() {
  if (!has_box_) return;
  bool moved = false;
  for (int i = 0; i < n_; ++i) {
    const double v = std::clamp(theta_(i), lower_(i), upper_(i));
    if (v != theta_(i)) {
      theta_(i) = v;
      moved = true;
    }
  }
  if (moved) ++health_.projections;
}

template <int N>
RlsHealth Rls<N>::health() const {
  RlsHealth h = health_;
  const double t = options_.method == RlsMethod::kNlms ? n_ * options_.initial_covariance : Trace();
  h.trace_p = t;
  double lo = std::numeric_limits<double>::infinity();
  double hi = 0.0;
  for (int i = 0; i < n_; ++i) {
    const double v = UsesUd() ? d_(i) : (UsesCovariance() ? p_(i, i) : 1.0);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  h.condition_estimate = lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
  h.wound_up = (bounded_ && t >= options_.trace_max * (1.0 - 1e-12)) ||
               t > n_ * options_.initial_covariance * (1.0 + 1e-9);
  return h;
}

// The sizes canalid uses are compiled once, in rls_instances_*.cc (the class and Update on a
// Vector regressor), instead of in every file that runs one: a size costs 10-20 s of compile time.
// Other sizes and regressor expressions are compiled where they are used, as before.
// `prefix` is `extern` or nothing, which cannot take the parentheses clang-tidy asks for.
// NOLINTBEGIN(bugprone-macro-parentheses)
#define CANALID_RLS_SIZE(prefix, N) \
  prefix template class Rls<N>;     \
  prefix template Rls<N>::Result Rls<N>::Update(const Eigen::MatrixBase<Rls<N>::Vector>&, double);
#define CANALID_RLS_SMALL_SIZES(prefix) \
  CANALID_RLS_SIZE(prefix, 1)           \
  CANALID_RLS_SIZE(prefix, 2)           \
  CANALID_RLS_SIZE(prefix, 3)           \
  CANALID_RLS_SIZE(prefix, 4)
#define CANALID_RLS_LARGE_SIZES(prefix) \
  CANALID_RLS_SIZE(prefix, 5)           \
  CANALID_RLS_SIZE(prefix, 6)           \
  CANALID_RLS_SIZE(prefix, 7)           \
  CANALID_RLS_SIZE(prefix, 8)
// NOLINTEND(bugprone-macro-parentheses)
CANALID_RLS_SMALL_SIZES(extern)
CANALID_RLS_LARGE_SIZES(extern)
CANALID_RLS_SIZE(extern, Eigen::Dynamic)

}  // namespace canalid::core
