#pragma once
#include <Eigen/Core>

#include "core/fractional/fractional_foptd.h"
#include "core/numerics/lag_line.h"
#include "core/signal/fractional_delay.h"

namespace canalid::core {

/// Sampling convention of every simulator here: u[k] is held over [k Ts, (k+1) Ts) (ZOH), y[k]
/// is the output at t = k Ts, the system is at rest with u = 0 before t = 0 (feed deviations
/// from the initial values).  A sub-sample delay tau = (d + f) Ts is applied exactly to the held
/// input: during [k Ts, k Ts + f Ts) the plant sees u[k-d-1], afterwards u[k-d] (ZohDelaySplit).
/// Streaming use: read output() (y[k]) then Advance(u[k]).  Allocation only in constructors.

/// Band and density of the Oustaloup approximation.  G = K/(1 + T s^alpha) is realised as
/// K/(1 + T s R(s)) with R ~ s^(alpha-1) (Oustaloup, -1 < alpha-1 < 1), so the static gain is
/// exactly K whatever the band; R is accurate over [low, high].
struct OustaloupOptions {
  double low_frequency_rad_s = 1e-4;
  double high_frequency_rad_s = 1e3;
  double sections_per_decade = 3.0;  ///< (0, 20]; at most 200 sections over the band (oustaloup.h)
};

/// The band used when none is given: [0.002 / H, 50 / Ts] rad/s with H = max(horizon_s,
/// 1000 Ts), widened to include [0.01, 10] x T^(-1/alpha) (the corner of 1/(1 + T s^alpha)),
/// 3 sections per decade.  Measured against the Mittag-Leffler truth at Ts = 0.15 s over 360 s,
/// T in [1.17, 48] s, alpha in [0.5, 1.8], sub-sample delays: worst error 0.28 % of K (at
/// alpha = 1.8; below 0.1 % inside the flume paper's alpha range), 2 sections per decade about the
/// same.
OustaloupOptions DefaultOustaloupOptions(const FractionalFoptdParams& params, double sample_time_s,
                                         double horizon_s);

/// Oustaloup simulator: the rational approximation above (N + 1 states for N sections) with the
/// delayed ZOH split discretised exactly (matrix exponential).  Per sample: one dense n x n
/// matrix-vector product (n = 17 at 2 sections per decade, 25 at 3, for a 360 s record at
/// Ts = 0.15 s).  alpha = 1 uses the exact one-state first order K/(1 + T s) (no
/// approximation: the ZOH result equals the continuous step response to rounding).
class OustaloupFoptdSimulator final {
 public:
  /// @throws std::invalid_argument on invalid params, sample_time_s <= 0, a delay over 1e7
  ///         samples or a bad band (OustaloupSections: density and section count bounded).
  OustaloupFoptdSimulator(const FractionalFoptdParams& params, double sample_time_s,
                          const OustaloupOptions& options);
  double output() const { return output_; }
  void Advance(double input);
  void Reset();
  int state_size() const { return static_cast<int>(state_.size()); }

 private:
  Eigen::MatrixXd phi_;
  Eigen::VectorXd gamma_previous_;
  Eigen::VectorXd gamma_current_;
  Eigen::RowVectorXd c_;
  Eigen::VectorXd state_;
  Eigen::VectorXd next_;
  ZohDelayLine delay_;
  double output_ = 0.0;
};

/// Grunwald-Letnikov (GL1) simulator on an internal grid h = Ts / substeps:
///   y_n = (K v_n - c sum_{j=1..L} w_j y_{n-j}) / (1 + c),  c = T h^-alpha,
/// where v_n is the mean of the delayed held input over (t_{n-1}, t_n] (exact for the delayed
/// ZOH split when h divides the interval).  The history is a LagLine so each step is
/// one contiguous dot product of length L (cost O(L) per internal step).  GL1 has O(h) error;
/// alpha = 1 uses the exact ZOH first order instead.
class GlFoptdSimulator final {
 public:
  /// @param substeps  internal steps per sample, >= 1.
  /// @param memory_length  L, number of past internal values kept, >= 1.
  /// @throws std::invalid_argument on a bad argument.
  GlFoptdSimulator(const FractionalFoptdParams& params, double sample_time_s, int substeps,
                   int memory_length);
  double output() const { return output_; }
  void Advance(double input);
  void Reset();

 private:
  FractionalFoptdParams params_;
  int substeps_;
  int memory_length_;
  double c_ = 0.0;
  Eigen::VectorXd weights_;          // w_1..w_L
  LagLine history_{1};               // y_{n-1}, y_{n-2}, ...: L of them (alpha != 1)
  Eigen::VectorXd previous_weight_;  // share of u_previous in each substep's input mean
  ZohDelayLine delay_;
  double output_ = 0.0;
  // alpha = 1: exact ZOH with split
  bool exact_first_order_ = false;
  double a_early_ = 0.0;
  double a_late_ = 0.0;
};

/// GL1 resolution that keeps the error at the sample times within ~0.5 % of K over the flume
/// paper's ranges and beyond (see fractional_simulator.cc): h <= min(Ts, 0.0125 s, T^(1/alpha) /
/// (40 + 400 max(0, alpha - 1))), rounded to a whole number of substeps (orders above 1 oscillate).
/// At Ts = 0.15 s that is 12 substeps or more: with full memory a 2,400-sample record costs
/// ~ (12 * 2400)^2 / 2 multiply-adds; use the Oustaloup simulator for long records and fits.
int DefaultGlSubsteps(const FractionalFoptdParams& params, double sample_time_s);

enum class FractionalSimMethod { kOustaloup, kGrunwaldLetnikov };

struct FractionalSimOptions {
  FractionalSimMethod method = FractionalSimMethod::kOustaloup;
  /// Oustaloup band; when low_frequency_rad_s <= 0 DefaultOustaloupOptions is used.
  OustaloupOptions oustaloup{0.0, 0.0, 3.0};
  int gl_substeps = 0;       ///< 0: DefaultGlSubsteps
  int gl_memory_length = 0;  ///< 0: the whole record (exact GL1, O(N^2)), or see below
  /// When > 0 (and gl_memory_length = 0): short memory L from the GL tail bound so that the
  /// static gain error |T h^-alpha S(L)| / (1 + ...) stays below this relative tolerance
  /// (GrunwaldLetnikovMemoryLength with tail_tolerance = tol h^alpha / T), capped at the record.
  double gl_static_gain_tolerance = 0.0;
};

/// The GL memory (internal steps) that SimulateFractionalFoptd uses for a record of `samples`.
int GlMemoryLength(const FractionalFoptdParams& params, double sample_time_s, int samples,
                   const FractionalSimOptions& options);

/// Simulates y (same length as u) with the chosen method; see the sampling convention above.
/// @throws std::invalid_argument on invalid params, sample_time_s <= 0 or an empty u.
Eigen::VectorXd SimulateFractionalFoptd(const FractionalFoptdParams& params,
                                        const Eigen::Ref<const Eigen::VectorXd>& input,
                                        double sample_time_s,
                                        const FractionalSimOptions& options = {});

}  // namespace canalid::core
