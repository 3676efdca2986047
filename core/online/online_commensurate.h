#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/numerics/ring_buffer.h"
#include "core/online/online_gl_regressor.h"
#include "core/online/rls.h"

namespace canalid::core {

/// The largest q of the online commensurate model: n = 2q states, 4q - 1 parameters.
inline constexpr int kMaxOnlineCommensurateQ = 4;

struct OnlineCommensurateOptions {
  int q = 2;                 ///< alpha = 1/q, 1..kMaxOnlineCommensurateQ
  int delay_samples = 0;     ///< nk >= 0 (known, as the frac-foptd and lpv kinds')
  int memory_samples = 200;  ///< GL short memory L >= 1 of every fractional difference
  RlsOptions rls;            ///< n = 4q - 1
  double input_abs_max = 1e9;
  double output_abs_max = 1e9;

  int order() const { return 2 * q; }
  int num_params() const { return 4 * q - 1; }
  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// The commensurate fractional state space model of core/fractional/commensurate_state_space.h
/// (alpha = 1/q, n = 2q states, unit static gain), identified online by recursive least squares
/// on the equation-error recursion of FitCommensurate's first stage:
///   -[D^2 y](k) = sum_{i=1..n-1} a_i [D^{(n-i) alpha} y](k-i) + a_n (y(k-n) - u(k-n-nk))
///                 - sum_{m=1..n-1} g_m [D^{m alpha} u](k-n+m-nk),   g_m = a_n c_m,
/// theta = [a_1..a_n, g_1..g_{n-1}], with [D^b s](k) = sum_{j=0..min(k, L)} w_j^(b) s(k-j) (GL
/// weights, short memory L) and samples before the first at rest (zero).  With L at least the
/// record's length and no forgetting it is the batch least squares (FitCommensurate with
/// refine = false) up to the prior P0 = p0 I.  Equation error: exact on noise-free data, biased
/// under output noise as the batch first stage is.  Feed deviations from rest.  A bad input is
/// replaced by the last good one; a bad output skips the update and enters the history as the
/// model's one-step prediction.  Allocates only in the constructor.  Deterministic.
class OnlineCommensurate final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineCommensurate(const OnlineCommensurateOptions& options);

  /// One sample of input and output.  True when the estimator was updated.
  bool Update(double u, double y);

  /// a_i, 1 <= i <= n, and its standard deviation.
  double a(int i) const { return rls_.theta()(i - 1); }
  double a_std(int i) const { return rls_.StandardDeviation(i - 1); }
  /// c_m = g_m / a_n, 1 <= m <= n - 1 (NaN while a_n = 0).
  double c(int m) const;
  /// The first-order standard deviations of c_1..c_{n-1} (from the covariance of (a_n, g_m))
  /// into out[0..n-2].  One covariance, O(n^3) for the UD form; no allocation.
  /// @pre out.size() >= n - 1.
  void CStandardDeviations(std::span<double> out) const;

  const Rls<Eigen::Dynamic>& estimator() const { return rls_; }
  const OnlineCommensurateOptions& options() const { return options_; }
  std::int64_t bad_inputs() const { return bad_inputs_; }
  std::int64_t bad_outputs() const { return bad_outputs_; }

 private:
  // [D^{m alpha} s](k) of the newest value `current` and `history` (history[0] = s(k-1)).
  double Difference(int m, double current, const RingBuffer<double>& history) const;

  OnlineCommensurateOptions options_;
  Rls<Eigen::Dynamic> rls_;
  std::vector<OnlineGlRegressor> orders_;  // [m - 1]: GL weights of order m alpha, m = 1..n-1
  RingBuffer<double> u_raw_;               // u(k-1), u(k-2), ... (L values)
  RingBuffer<double> y_raw_;               // y(k-1), y(k-2), ...
  // [m]: [D^{m alpha} s](k), (k-1), ... for m = 0..n-1 (m = 0: s itself).
  std::vector<RingBuffer<double>> du_;
  std::vector<RingBuffer<double>> dy_;
  Eigen::VectorXd phi_;
  mutable Eigen::MatrixXd covariance_;  // work for c_std
  double u_good_ = 0.0;
  std::int64_t k_ = -1;
  std::int64_t bad_inputs_ = 0;
  std::int64_t bad_outputs_ = 0;
};

}  // namespace canalid::core
