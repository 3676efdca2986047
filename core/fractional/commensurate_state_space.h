#pragma once
#include <Eigen/Core>

#include "core/numerics/metrics.h"

namespace canalid::core {

/// The LPV paper's commensurate (rational) order discrete state space, alpha = 1/q, n = 2q states:
///   Delta^alpha x[k+1] = A x[k] + B u[k - nk],  y[k] = C x[k],
///   Delta^alpha x[k+1] = sum_{j=0..k+1} w_j x[k+1-j]   (GL weights of order alpha, full memory),
///   A = companion: ones on the superdiagonal, last row -[a_n, ..., a_1];  B = a_n e_n;
///   C = [1, c_1, ..., c_{n-1}].
/// With lambda = z (1 - z^-1)^alpha the transfer function is
///   Y/U = z^-nk a_n (1 + c_1 lambda + ... + c_{n-1} lambda^{n-1}) / (lambda^n + a_1 lambda^{n-1}
///         + ... + a_n),
/// unit static gain (Delta^alpha of a constant tends to 0).  The LPV paper's tables map as: alpha =
/// 0.5, a = (b1, b2, b3, b4), c = (b7, b6, b5); alpha = 0.25, a = (c1..c8), c = (c15, ..., c9). q =
/// 1 is the integer second-order model.
struct CommensurateModel {
  int q = 2;              ///< alpha = 1/q, q >= 1
  Eigen::VectorXd a;      ///< a_1..a_n, n = 2q
  Eigen::VectorXd c;      ///< c_1..c_{n-1}
  int delay_samples = 0;  ///< nk >= 0
  double alpha() const { return 1.0 / q; }
  int order() const { return 2 * q; }
};

/// @throws std::invalid_argument when q < 1, sizes do not match n = 2q, delay < 0 or values are
///         not finite.
void Validate(const CommensurateModel& model);

/// Simulates y (same length as u) from rest (x = 0, u = 0 before k = 0; feed deviations).
/// memory_length L > 0 truncates the GL sum to j <= L (short memory); 0 keeps the full history
/// (O(N^2 n) work).  Allocates the history once per call.
/// @throws std::invalid_argument on an invalid model or memory_length < 0.
Eigen::VectorXd SimulateCommensurate(const CommensurateModel& model,
                                     const Eigen::Ref<const Eigen::VectorXd>& input,
                                     int memory_length = 0);

struct CommensurateFitOptions {
  bool refine = true;  ///< LM on the simulation error after the linear least squares
  int max_iterations = 100;
  int memory_length = 0;  ///< passed to SimulateCommensurate during the refinement
};

struct CommensurateFitResult {
  CommensurateModel model;     ///< refined (or the least-squares one when refine = false)
  CommensurateModel initial;   ///< equation-error least squares
  FitMetrics metrics;          ///< simulation of `model` vs the measured output
  Eigen::VectorXd simulated;   ///< model output, output offset added back
  double input_offset = 0.0;   ///< u[0], removed before fitting
  double output_offset = 0.0;  ///< y[0], removed before fitting
  bool converged = false;
};

/// Identifies a, c for given q and delay from a record at rest at k = 0 (deviations from u[0],
/// y[0]).  Stage 1, linear least squares on the GL-expanded input-output recursion (exact for
/// noise-free data, equation-error biased under noise):
///   D^2 y(k) + sum_{i=1..n} a_i [D^{(n-i) alpha} y](k-i)
///       = a_n sum_{m=0..n-1} c_m [D^{m alpha} u](k-n+m-nk),   c_0 = 1,
/// with [D^b s](k) = sum_{j=0..k} w_j^(b) s(k-j) (full-memory GL), linear in (a, a_n c).
/// Stage 2 (the LPV paper): Levenberg-Marquardt of (a, c) on the simulation error, started there.
/// @throws std::invalid_argument on sizes, q < 1, delay < 0, sample_time_s <= 0, too few
///         samples (< 10 n + delay, n = 2q), or an input that never moves from input[0].
CommensurateFitResult FitCommensurate(const Eigen::Ref<const Eigen::VectorXd>& input,
                                      const Eigen::Ref<const Eigen::VectorXd>& output, int q,
                                      int delay_samples, double sample_time_s,
                                      const CommensurateFitOptions& options = {});

/// As FitCommensurate with the delay unknown: the least-squares model is fitted for every nk in
/// 0..max_delay_samples (the GL differences are computed once), the one whose simulation error
/// is smallest is kept and refined.  Cost: one O(N^2 n) simulation per candidate delay.
/// @throws std::invalid_argument as FitCommensurate (with max_delay_samples for the delay).
CommensurateFitResult FitCommensurateScanDelay(const Eigen::Ref<const Eigen::VectorXd>& input,
                                               const Eigen::Ref<const Eigen::VectorXd>& output,
                                               int q, int max_delay_samples, double sample_time_s,
                                               const CommensurateFitOptions& options = {});

}  // namespace canalid::core
