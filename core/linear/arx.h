#pragma once
#include <Eigen/Core>
#include <vector>

namespace canalid::core {

/// Largest ARX orders accepted: na and each nb_i at most kMaxArxOrder, na + sum(nb) at most
/// kMaxArxParameters (the regressor matrix has that many columns), each nk_i at most
/// kMaxArxDelaySamples (so that nb_i + nk_i - 1 and every index derived from it fit an int).
inline constexpr int kMaxArxOrder = 1000;
inline constexpr int kMaxArxParameters = 1000;
inline constexpr int kMaxArxDelaySamples = 10000000;

/// Orders of a multi-input ARX model in MATLAB's convention:
///   y(t) + a_1 y(t-1) + ... + a_na y(t-na)
///     = sum_i [b_i1 u_i(t-nk_i) + ... + b_i,nb_i u_i(t-nk_i-nb_i+1)] + e(t)
/// so `na=2 nb=2 nk=1` is y(t) + a1 y(t-1) + a2 y(t-2) = b1 u(t-1) + b2 u(t-2).
/// nk_i = 0 is direct feedthrough; nb_i = 0 leaves input i out of the model.  A constant input
/// column (all ones, nb=1, nk=0) estimates an offset.
struct ArxOrders {
  int na = 2;
  std::vector<int> nb;  ///< one per input column of u, >= 0
  std::vector<int> nk;  ///< one per input column of u, >= 0
  /// na + sum(nb)
  int num_parameters() const;
  /// The 0-based index of the first sample whose regressors all exist:
  /// max(na, max_i(nb_i + nk_i - 1)) over inputs with nb_i > 0.
  int min_first_sample() const;
  /// @throws std::invalid_argument naming the field, the value and the allowed range
  ///         (0 <= na, nb_i <= kMaxArxOrder, 0 <= nk_i <= kMaxArxDelaySamples, sizes ==
  ///         num_inputs, 1 <= na + sum(nb) <= kMaxArxParameters).  Call it before the other
  ///         members on orders from outside: they assume these bounds.
  void Validate(Eigen::Index num_inputs) const;
};

/// A fitted ARX model (see ArxOrders for the equation) and its statistics.
struct ArxModel {
  ArxOrders orders;
  Eigen::VectorXd a;               ///< a_1..a_na (the leading 1 of A(q) is not stored)
  std::vector<Eigen::VectorXd> b;  ///< per input: b_1..b_nb (b_1 multiplies u(t-nk))
  /// theta = [a_1..a_na, b_1 of input 0.., b_1 of input 1.., ...] and its estimated covariance
  /// sigma^2 (Phi^T Phi)^{-1}, computed from the QR factor as sigma^2 R^{-1} R^{-T} (no normal
  /// equations), with sigma^2 = SSR / (N - d) the unbiased residual variance.
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;
  Eigen::VectorXd parameter_std;  ///< sqrt(diag(covariance))
  /// MATLAB's loss function V = SSR / N: the mean squared one-step residual over the N
  /// equations used.
  double loss = 0.0;
  double noise_variance = 0.0;  ///< sigma^2 = SSR / (N - d)
  /// Akaike's criterion, normalised form: log(V) + 2 d / N (d parameters, N equations), which
  /// is MATLAB's default `aic(sys)` = `aic(sys,'nAIC')` = sys.Report.Fit.nAIC.  MATLAB's raw
  /// `aic(sys,'aic')` is N log(V) + 2 d + N (log(2 pi) + 1) for one output.  -infinity when the
  /// fit is exact (V = 0, noise-free data): check before writing it to JSON.
  double aic = 0.0;
  double fpe = 0.0;               ///< Akaike's final prediction error V (1 + d/N) / (1 - d/N)
  Eigen::Index first_sample = 0;  ///< 0-based index of the first equation (time t)
  Eigen::Index num_samples = 0;   ///< N: equations used, t = first_sample .. size-1
  int num_parameters() const { return static_cast<int>(parameters.size()); }
};

/// Least-squares ARX fit: builds the regressor matrix Phi (row t = [-y(t-1)..-y(t-na),
/// u_i(t-nk_i)..u_i(t-nk_i-nb_i+1) for each input]) for t = first_sample..N-1 and solves
/// min ||Y - Phi theta|| with a column-pivoting Householder QR.  No demeaning: detrend first.
/// @param y  output, N samples.  @param u  N x m inputs (one column per input).
/// @param first_sample  first equation index; -1 uses orders.min_first_sample(), the first sample
///        whose regressors all exist in the record (no zero padding).  A later start lets several
///        models share one data window (delay scans, comparisons with Octave).
/// @throws std::invalid_argument on bad orders or sizes, first_sample < min_first_sample(), fewer
///         equations than parameters, non-finite data, or a rank-deficient regressor (the message
///         names the rank: the input is not persistently exciting for these orders).
ArxModel FitArx(const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::MatrixXd>& u, const ArxOrders& orders,
                Eigen::Index first_sample = -1);

/// Builds the ARX regressor matrix rows t = first_sample..N-1 (see FitArx).
/// @pre the arguments have been validated as in FitArx.
Eigen::MatrixXd ArxRegressors(const Eigen::Ref<const Eigen::VectorXd>& y,
                              const Eigen::Ref<const Eigen::MatrixXd>& u, const ArxOrders& orders,
                              Eigen::Index first_sample);

/// Pure simulation (the model's own past outputs, not the measured ones):
///   y_sim(t) = -sum_j a_j y_sim(t-j) + sum_i sum_j b_ij u_i(t-nk_i-j+1),
/// with y_sim(t) = y_initial(t) for t < y_initial.size() and every value before time 0 taken as 0
/// (simulate deviations from an operating point, or pass the first measured outputs).
/// @throws std::invalid_argument if u has the wrong number of columns or y_initial is longer
///         than u.
Eigen::VectorXd SimulateArx(const ArxModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                            const Eigen::Ref<const Eigen::VectorXd>& y_initial = Eigen::VectorXd());
/// The same into `y_sim` (u.rows() values; e.g. a core::LargeBuffer's).
/// @throws std::invalid_argument as above, or if y_sim.size() != u.rows().
void SimulateArx(const ArxModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                 const Eigen::Ref<const Eigen::VectorXd>& y_initial,
                 Eigen::Ref<Eigen::VectorXd> y_sim);

/// One-step-ahead prediction from measured data:
///   y_hat(t) = -sum_j a_j y(t-j) + sum_i sum_j b_ij u_i(t-nk_i-j+1),
/// values before time 0 taken as 0 (so only t >= model.first_sample match the fit's residuals).
/// @throws std::invalid_argument on mismatched sizes.
Eigen::VectorXd PredictArx(const ArxModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::MatrixXd>& u);

}  // namespace canalid::core
