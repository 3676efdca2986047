#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/linear/integrator_wave_model.h"

namespace canalid::core {

/// A kind of local (LTI) model for LPV identification (the LPV paper, docs/references.md).
/// - fit(u, y, Ts) -> parameter vector, on one contiguous record at a single operating point
///   (raw signals: the kind removes its own offsets);
/// - simulate(params, du, Ts) -> the model's response to du = u - u[0] from rest (deviation).
/// Parameters are real numbers that can be interpolated (an integer delay is carried as a real
/// and rounded when simulating).
struct LocalModelKind {
  std::string name;
  std::vector<std::string> parameter_names;
  std::function<Eigen::VectorXd(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double ts)> fit;
  std::function<Eigen::VectorXd(const Eigen::VectorXd& params, const Eigen::VectorXd& du,
                                double ts)>
      simulate;
};

/// First-order ARX with delay, y[k] = -a1 y[k-1] + b1 u[k-nk] (+ a constant absorbing the
/// operating point), nk in 1..max_delay_samples chosen by least-squares residual.
/// Parameters [a1, b1, nk].
/// @throws std::invalid_argument if max_delay_samples < 1.
LocalModelKind FirstOrderArxKind(int max_delay_samples);

/// Fractional FOPTD (fractional_foptd_fit.h).  Parameters [gain, time_constant_s, alpha,
/// delay_s].  Simulation with the Oustaloup simulator.
LocalModelKind FractionalFoptdKind(const FractionalFoptdFitOptions& options = {});

/// The LPV paper's commensurate fractional state space of order alpha = 1/q
/// (commensurate_state_space.h), the delay chosen in 0..max_delay_samples
/// (FitCommensurateScanDelay).  Parameters [a_1..a_n, c_1..c_{n-1}, nk].
/// @throws std::invalid_argument if q < 1 or max_delay_samples < 0.
LocalModelKind CommensurateKind(int q, int max_delay_samples,
                                const CommensurateFitOptions& options = {});

/// The integrator-with-waves model k e^{-tau s}/(s (S s^2 + M s + 1)) (integrator_wave_model.h).
/// Parameters [gain, s_coeff_s2, m_coeff_s, delay_s].
LocalModelKind IntegratorWaveKind(const IntegratorWaveFitOptions& options = {});

/// Values of the polynomial p_1 theta^d + ... + p_d theta + p_{d+1} (coefficients highest degree
/// first, as in the LPV paper: p1 theta^2 + p2 theta + p3).
double EvaluatePolynomial(const Eigen::Ref<const Eigen::VectorXd>& coefficients, double theta);

/// Least-squares polynomial of the given degree through (theta_i, value_i), highest degree first.
/// Vandermonde columns are scaled by max|theta| before the QR solve for conditioning.
/// @throws std::invalid_argument if sizes differ, degree < 0 or fewer points than degree + 1.
Eigen::VectorXd FitPolynomial(const Eigen::Ref<const Eigen::VectorXd>& theta,
                              const Eigen::Ref<const Eigen::VectorXd>& values, int degree);

/// The global LPV model: every local parameter as a polynomial in theta.
struct LpvModel {
  std::string kind;
  std::vector<std::string> parameter_names;
  int degree = 2;
  Eigen::MatrixXd coefficients;  ///< one row per parameter, highest degree first
  /// Parameters at theta (the interpolated local model).
  Eigen::VectorXd Evaluate(double theta) const;
};

/// One operating point: the band [theta_low, theta_high) and the longest contiguous run of the
/// record whose theta lies in it.
struct LpvOperatingPoint {
  double theta_low = 0.0;
  double theta_high = 0.0;
  double theta_mean = 0.0;  ///< mean theta over the run (where the polynomial is fitted)
  Eigen::Index start = 0;   ///< first sample of the run
  Eigen::Index length = 0;
  Eigen::VectorXd local_params;  ///< the local fit
  double local_mae = 0.0;        ///< MAE of the local model on its run
  double lpv_mae = 0.0;          ///< MAE of the LPV model evaluated at theta_mean on the run
};

/// Runs per band: for each band [edges[i], edges[i+1]) the longest contiguous run of samples
/// with theta in the band (length 0 when there is none).
/// @throws std::invalid_argument unless edges are strictly increasing (at least 2).
std::vector<LpvOperatingPoint> SplitByScheduling(const Eigen::Ref<const Eigen::VectorXd>& theta,
                                                 const std::vector<double>& edges);

struct LpvIdentification {
  LpvModel model;
  std::vector<LpvOperatingPoint> points;  ///< the bands used (runs of at least min_samples)
};

/// The LPV paper's two-step LPV identification: split by theta into bands, fit one local model per
/// band (kind.fit on the band's run), fit every parameter as a polynomial of `degree` in the
/// runs' mean theta, and validate per operating point with MAE (the LPV paper's Tables 8-9) for
/// both the local and the interpolated model.  MAE compares kind.simulate(params, u - u[0]) plus
/// the least-squares constant offset with y over the run.
/// @throws std::invalid_argument on size mismatch, sample_time_s <= 0, bad edges, or fewer than
///         degree + 1 usable bands (runs of at least min_samples).
LpvIdentification IdentifyLpv(const Eigen::Ref<const Eigen::VectorXd>& input,
                              const Eigen::Ref<const Eigen::VectorXd>& output,
                              const Eigen::Ref<const Eigen::VectorXd>& theta, double sample_time_s,
                              const std::vector<double>& edges, const LocalModelKind& kind,
                              int degree = 2, int min_samples = 50);

/// Simulates a FirstOrderArxKind LPV model along a scheduling trajectory (deviations, from rest):
///   y[k] = -a1(theta[k]) y[k-1] + b1(theta[k]) du[k - max(1, round(nk(theta[k])))].
/// @throws std::invalid_argument if the model is not of that kind or sizes differ.
Eigen::VectorXd SimulateLpvArx(const LpvModel& model, const Eigen::Ref<const Eigen::VectorXd>& du,
                               const Eigen::Ref<const Eigen::VectorXd>& theta);

}  // namespace canalid::core
