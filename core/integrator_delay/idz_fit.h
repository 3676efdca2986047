#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/numerics/metrics.h"

namespace canalid::core {

/// What determined the IDZ fit's outflow gain p22.
enum class OutflowGainSource {
  kData,   ///< fitted: the outflow moved on its own (not driven by the level)
  kPrior,  ///< the prior (from the geometry, `canalid theory`), held in the fit
  kNone,   ///< neither: p22 = 0 (the outflow was held, or it followed the level with no prior)
};
const char* OutflowGainSourceName(OutflowGainSource source);

/// The standard deviation of a p22 prior from the geometry when none is given, relative to it:
/// the theory's two-part profile was within 12.6 % of the linearised equations on the true profile
/// for the 16 ASCE pools (idz_theory_profile_test); 20 % leaves room for the roughness and the
/// structure's own response.
inline constexpr double kIdzPriorRelativeStd = 0.2;

struct IdzFitOptions {
  int min_nk = 0;
  int max_nk = -1;  ///< < 0: a third of the record
  /// p22 prior (s/m^2, >= 0) and its standard deviation; a negative prior means none (NaN is
  /// refused).  Use the
  /// low-frequency gain of the theory (IdzTheory::outflow_gain_low_frequency_s_per_m2): it is the
  /// one a level-driven outflow couples into the level.
  double p22_prior_s_per_m2 = -1.0;
  double p22_prior_std_s_per_m2 = 0.0;
};

/// The sampled IDZ level equation that FitIdz fits and `canalid simulate` runs.
struct IdzLevelModel {
  int nk = 0;
  double b = 0.0;  ///< Ts / A
  double p21_s_per_m2 = 0.0;
  double p22_s_per_m2 = 0.0;
  double offset_m = 0.0;
  double drift_m_per_sample = 0.0;
};

/// y(k) = b Q(k) + (p21 - b) q_in(k - nk) - p22 q_out(k) + c + d (k - k0) for k = k0..N-1 (Q as
/// in IdzFit).  @throws std::invalid_argument unless 0 <= nk <= k0 < N and the sizes agree.
Eigen::VectorXd IdzLevel(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                         const Eigen::Ref<const Eigen::VectorXd>& q_out, const IdzLevelModel& model,
                         int k0);

/// The IDZ model of a pool identified from a record (Litrico & Fromion 2004's structure):
///   y(k) = b Q(k) + (p21 - b) q_in(k - nk) - p22 q_out(k) + c + d (k - k0),
///   Q(k) = sum_{j=k0..k} (q_in(j - nk) - q_out(j - 1)),  b = Ts / A,
/// the zero-order hold of the continuous model y = (1/(A s) + p21) e^{-tau s} q_in - (1/(A s) +
/// p22) q_out with tau = nk Ts: the inflow that arrives at sample k has added no volume by then
/// (b (Q(k) - q_in(k - nk)) sums the delayed inflow up to sample k - 1, as Q already does the
/// outflow), while its front p21 q_in(k - nk) is there.  So p21 is the continuous model's, the
/// one `canalid theory` computes.  (Q(k) holds q_in(k - nk), the ID fit's convention: with the
/// front's column the two forms fit the same, and Q's would report p21 - b, 9.5 % of p21 on ASCE
/// canal 2 pool 2 at Ts = 60 s.)
struct IdzFit {
  int nk = 0;
  double sample_time_s = 1.0;
  double delay_s() const { return nk * sample_time_s; }
  double area_m2 = 0.0;
  double p21_s_per_m2 = 0.0;
  double p22_s_per_m2 = 0.0;
  /// Standard deviations: sigma^2 (X'X)^-1 with sigma^2 from the residuals, plus, with a prior,
  /// the prior's own uncertainty carried through the fit (the estimates are linear in p22).
  /// The residuals of a level record are correlated, so these are lower bounds.
  double area_std_m2 = 0.0;
  double p21_std_s_per_m2 = 0.0;
  double p22_std_s_per_m2 = 0.0;
  OutflowGainSource p22_source = OutflowGainSource::kNone;
  std::string p22_reason;  ///< why that source
  bool outflow_moves = false;
  bool outflow_follows_level = false;  ///< closed loop (ClosedLoopDetector's rule)
  double outflow_level_correlation = 0.0;
  double offset_m = 0.0;
  double drift_m_per_sample = 0.0;
  int first_sample = 0;  ///< k0
  Eigen::VectorXd loss_by_nk;
  FitMetrics metrics;               ///< fitted level against measured, samples k0..N-1
  Eigen::VectorXd simulated_level;  ///< samples k0..N-1
  std::vector<std::string> warnings;

  IdzLevelModel level_model() const {
    return IdzLevelModel{nk,       sample_time_s / area_m2, p21_s_per_m2, p22_s_per_m2,
                         offset_m, drift_m_per_sample};
  }
};

/// Fits the IDZ model: for each nk the regression above by least squares (QR) with p21 >= 0 (as
/// the ID fit: a negative p21 is held at 0, with a warning), the nk with the smallest residual
/// kept.  With p21 held at 0 the level is b (Q(k) - q_in(k - nk)): the ID fit's at nk + 1.  p22 is
///  - fitted (kData) when the outflow moves (std above 2 % of the inflow's) and does not follow
///    the level (r <= 0.3 between the detrended outflow and level: a level-driven outflow rises
///    with the level, while one moved on its own lowers it, r < 0): a second structure moved on
///    its own, a pump, an offtake;
///  - held at the prior (kPrior) otherwise, when there is one: with a level-driven outflow
///    q_out ~ q0 + g y the term p22 q_out is p22 g y, which no regression can tell from the
///    integrator (without it the area reads A (1 + p22 g));
///  - 0 (kNone) with no prior, with a warning when the outflow follows the level.
/// @throws std::invalid_argument as ValidatePoolRecord, on a bad delay range or prior, or with
///         fewer than 20 samples after the longest delay.
IdzFit FitIdz(const Eigen::Ref<const Eigen::VectorXd>& q_in,
              const Eigen::Ref<const Eigen::VectorXd>& q_out,
              const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
              const IdzFitOptions& options = {});

}  // namespace canalid::core
