#pragma once
#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/integrator_delay/closed_loop_detector.h"
#include "core/integrator_delay/integrator_delay_model.h"
#include "core/numerics/lag_line.h"
#include "core/online/estimator_bank.h"
#include "core/online/online_three_step.h"
#include "core/online/rls.h"
#include "core/online/rls_bank.h"
#include "core/online/rls_iv.h"

namespace canalid::core {

/// Bits of IntegratorDelaySnapshot::flags, the same values as canalid.model_snapshot_t's FLAG_*
/// (see docs/lcm-channels.md).
inline constexpr int kFlagNan = 1;             ///< a parameter or P is NaN or infinite
inline constexpr int kFlagWindup = 2;          ///< RlsHealth::wound_up: trace(P) above n p0
inline constexpr int kFlagLowExcitation = 4;   ///< information_min below the health threshold
inline constexpr int kFlagIllConditioned = 8;  ///< condition_number > condition_max
inline constexpr int kFlagFrozen = 16;         ///< the last sample carried no information
inline constexpr int kFlagOutOfBounds = 32;    ///< A <= 0 or not finite, or nk at a bank edge

/// Thresholds of the health flags of IntegratorDelaySnapshot (OnlineIntegratorDelayBank::Snapshot).
struct IntegratorDelayHealthOptions {
  /// kFlagIllConditioned above it: the 2-norm condition number of the estimator's P.
  double condition_max = 1e12;
  /// kFlagLowExcitation below max(information_min_per_p0 / p0, information_min_floor): the
  /// smallest eigenvalue of P^-1 (the information matrix of the data in the estimator's memory,
  /// plus the prior's 1 / p0 and what forgetting leaves of it).  100: some direction of theta has
  /// gained less than ~99 times the prior's information, i.e. the data has not identified all
  /// parameters.
  double information_min_per_p0 = 100.0;
  /// The threshold's floor, in the regressors' units squared: 100 / 1e6, the threshold at the P0
  /// the daemon used before the least-squares kinds' 1e10.  Without it a P0 of 1e10 lowers the
  /// threshold to 1e-8, and the first absurd estimates of a bank (area 2.6e6 m2 from 139 samples
  /// in DaemonSoak) went out unflagged.
  double information_min_floor = 1e-4;
  /// kFlagLowExcitation also when the snapshot's flow_level_rms_m is below it (m): the flow term
  /// explains a level swing finer than a canal's level sensor resolves (radar and pressure
  /// gauges: about 1 mm), so the area rests on rounding, not on a measured response.  Before any
  /// experiment the inflow and outflow of a pool at rest balance; in DaemonSoak the bank fitted
  /// areas of 2.6e6 m^2 (76 x the pool's) with a relative standard deviation of 20 % and
  /// information 3.7e-4, above the floor, from a swing of about 4e-8 m (f32 levels from canalsim).
  double level_resolution_m = 1e-4;
  /// The kFlagLowExcitation threshold of an estimator started at P0 = p0 I.
  double InformationMin(double p0) const {
    return std::max(information_min_per_p0 / p0, information_min_floor);
  }
  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// Options of OnlineIntegratorDelayBank.
struct OnlineIntegratorDelayOptions {
  double sample_time_s = 1.0;  ///< Ts > 0
  int min_delay_samples = 0;   ///< smallest candidate nk >= 0
  int max_delay_samples = 0;   ///< largest candidate nk >= min_delay_samples
  RlsOptions rls;              ///< per candidate (n = 3, or 4 with wave_front_term); UD, lambda 1
  /// Adds IDZ's wave-front regressor q_in(k - nk) (gain p21) as in the batch FitIntegratorDelay, so
  /// that with lambda = 1 and a large P0 the bank equals FitIntegratorDelay's open-loop fit.  Off
  /// by default here (the daemon's configured banks keep the 3-parameter form); `canalid identify
  /// --online` turns it on.
  bool wave_front_term = false;
  /// p21 >= 0 as in the batch fit (FitIntegratorDelay refits without the wave-front column when
  /// its gain comes out negative); wave_front_term only.  Each candidate's recursion stays
  /// unconstrained; when its p21 is negative, its snapshot and the a-priori error its selector
  /// sees use the equality-constrained estimate theta - G e2 p21 / G_22 (G = P, or the IV gain
  /// (Z' Phi)^-1), which with lambda = 1 and a large P0 is exactly the batch refit without the
  /// column.  (Projecting theta inside the recursion instead, RlsOptions' box, leaves P describing
  /// the unconstrained fit: the clamped candidates never recovered, e.g. nk 8-13 of 0..280 on the
  /// fixed-gate pool 2 record ended with areas of 0-748 m^2, so the bank could not choose the
  /// batch's nk = 12.)
  bool wave_front_non_negative = false;
  /// IDZ's level equation (core::IdzLevel, the online `idz` kind): the integral without the
  /// sample's own delayed inflow, Q_nk(k) - q_in(k - nk), the zero-order hold of the continuous
  /// model, so that p21 is the continuous model's, as the batch FitIdz reports it.  The same fit
  /// as Q_nk's (the columns span the same space), whose p21 is this one's less b; with p21 held at
  /// 0 a candidate is the plain ID regression at nk + 1.  wave_front_term only.  The three-step
  /// estimate (closed_loop kThreeStep, p21 = 0) keeps Q_nk.
  bool idz_level_equation = false;
  /// The delay's choice.  Default kResidual: the candidate of smallest least-squares loss (with
  /// p21 >= 0: of the reported, constrained fit), so that with lambda = 1 the bank's delay is the
  /// batch FitIntegratorDelay scan's at every sample.  The least-squares bank only: the IV bank
  /// (closed_loop) always chooses by the a-priori error, an IV estimate not being a least-squares
  /// one.  kPredictionError, the choice before (see BankCriterion), depended on which candidate
  /// led while the estimators converged: on the demo's closed-loop pool 2 record, P0 = 1e6
  /// settled on 480 s and P0 = 1e10 on 660 s, the batch scan's delay.
  BankSelectorOptions selector{.criterion = BankCriterion::kResidual};
  /// Re-centring period of the regressor (samples): 0 = automatic, i.e. never for lambda = 1 and
  /// ceil(1 / (1 - lambda)) (one memory length) otherwise; < 0 = never.
  int recentre_samples = 0;
  double flow_abs_max_m3s = 1e5;  ///< |q| above it (or non-finite) is an absurd flow
  double level_abs_max_m = 1e4;   ///< |y| above it (or non-finite) is an absurd level
  /// Closed loop (a downstream gate whose outflow follows the level, so the measured total flow
  /// in Q_nk is correlated with the level's errors).  kOn: every candidate is fitted by
  /// instrumental-variable RLS (IvRls, same regressor phi) with the instrument
  ///   z = [Qin_nk(k), q_in(k - nk), 1, k - k0]  (without q_in(k - nk) when !wave_front_term),
  ///   Qin_nk(k) = sum_{j=k0..k} (q_in(j - nk) - q_ref),  q_ref the first good inflow,
  /// i.e. the integrated delayed inflow, the excitation, which does not see the level's errors
  /// (FitIntegratorDelay's IV cross-check; with lambda = 1 and a large P0 each candidate equals the
  /// batch IV estimate (Z' Phi)^-1 Z' y).  kOff (default, the daemon's behaviour): least squares
  /// (Rls). kAuto: both run until closed_loop_window_samples regression samples from k0 have been
  /// seen, then ClosedLoopDetector (FitIntegratorDelay's test: outflow std above 2 % of the
  /// inflow's and |corr(detrended q_out, detrended level)| > 0.3, over those samples) picks one for
  /// good; the snapshots report the least-squares bank until then.  The per-sample cost doubles
  /// during the window.  The IV estimators take forgetting, P0, trace_max, the box and the sample
  /// guards from `rls`; its method and innovation guards do not apply (IvRls: exponential
  /// forgetting only). See outflow_direct_gain_s_per_m2 for what closed-loop data cannot give.
  /// kThreeStep: the three-step method online (OnlineThreeStep, one per
  /// candidate, fed u = q_in(k - nk), t = u - q_out(k - 1) and the fitted output from k0 on);
  /// snapshots report the three-step estimate (p21 = 0, as the batch's closed-loop fit) at the nk
  /// chosen by the IV bank, which runs alongside (as for kOn).  Step (1) needs a delay criterion
  /// the loop does not bias; measured on the fixed-gate ASCE canal 2 pool 2 record (true 682 s):
  /// the IV bank's choice is 720 s (the batch scan's too); the least-squares bank's was 780 s
  /// while p21 >= 0 was an RLS box (see wave_front_non_negative; there the zero-DC-gain F_hat
  /// never comes out stable and step 3 has no flow to fit) and is 720 s now, but it sees the
  /// loop's bias; a selector on the three-step candidates' own level errors 540 s (area 23641
  /// m^2, -31 %).
  /// Step (3) takes forgetting, P0 and the sample guards from `rls` (not its box), step (2) its
  /// forgetting; the rest from three_step.
  ClosedLoopMode closed_loop = ClosedLoopMode::kOff;
  ThreeStepOptions three_step;  ///< kThreeStep only; regression and recentre_samples are set here
  int closed_loop_window_samples = 200;  ///< kAuto's decision window, 3..1e9 samples
  /// IDZ's direct outflow gain p22 (s/m^2, >= 0; Litrico & Fromion 2004, from the geometry): the
  /// fitted output is y(k) + p22 q_out(k) instead of y(k).  In open loop q_out is (nearly)
  /// constant and p22 q_out goes into c.  In closed loop with a gate q_out ~ q0 + g y, the term
  /// becomes p22 g y and cannot be told apart from b: with p22 = 0 the estimate is that of
  /// A (1 + p22 g) (measured: 44215 m^2, 34113 x 1.32 = 44.9k, on ASCE canal 2 pool 2, g = 14.6
  /// m^2/s), and no estimator of this regression can do better from the data alone.  Snapshots' c
  /// is then the offset of y + p22 q_out.  0 = plain ID.
  double outflow_direct_gain_s_per_m2 = 0.0;
  IntegratorDelayHealthOptions health;  ///< thresholds of IntegratorDelaySnapshot::flags

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// One candidate's (or the selected) integrator-delay model.
struct IntegratorDelaySnapshot {
  bool valid = false;        ///< false until the first regression sample
  std::int64_t sample = -1;  ///< index k of the last sample (0 = first sample given)
  int delay_samples = -1;    ///< nk
  double delay_s = 0.0;      ///< nk Ts
  double b = 0.0;            ///< backwater coefficient (s/m^2 per sample): level per m^3/s x sample
  double wave_front_gain_s_per_m2 = 0.0;  ///< p21 (0 without wave_front_term)
  double c_m = 0.0;                       ///< offset at k = k0
  double d_m = 0.0;                       ///< drift per sample
  double area_m2 = 0.0;                   ///< Ts / b
  double b_std = 0.0;                     ///< standard deviations from sigma2 P
  double c_std_m = 0.0;
  double d_std_m = 0.0;
  double area_std_m2 = 0.0;         ///< Ts b_std / b^2 (first order)
  double prediction_error_m = 0.0;  ///< last a-priori error
  double innovation_std_m = 0.0;    ///< sqrt(sigma2)
  /// What the selector compares: the residual sum of squares of the reported fit (kResidual,
  /// the least-squares bank's default) or the weighted squared a-priori error (kPredictionError,
  /// and always for the IV bank).
  double loss = 0.0;
  RlsHealth health;
  /// 2-norm condition number of the estimator's P (exact: a fixed-size eigen decomposition).
  double condition_number = 1.0;
  /// Smallest eigenvalue of P^-1, 1 / lambda_max(P): the information in the least excited
  /// direction of theta (regressor units squared over sigma2).
  double information_min = 0.0;
  /// The RMS over the estimator's memory of the level swing the flow term explains:
  /// |b| rms(Q_nk orthogonal to the other regressors) = |b| / sqrt(P_bb N), N the updates or,
  /// with forgetting lambda < 1, at most the memory 1 / (1 - lambda) (m; NaN when P_bb is not
  /// positive and finite).  Compared with health.level_resolution_m.
  double flow_level_rms_m = 0.0;
  int flags = 0;  ///< kFlag* bits, IntegratorDelaySnapshotFlags of this snapshot
};

/// The health flags of a snapshot of a bank with these options (kFlag*):
///   kFlagNan: b, c, d, A or trace(P) not finite;  kFlagWindup: health.wound_up;
///   kFlagLowExcitation: information_min < max(health.information_min_per_p0 / p0,
///     health.information_min_floor), or flow_level_rms_m < health.level_resolution_m;
///   kFlagIllConditioned: condition_number > options.health.condition_max (or not finite);
///   kFlagFrozen: health.frozen;
///   kFlagOutOfBounds: A <= 0 or not finite, or nk = max_delay_samples, or nk = min_delay_samples
///     > 0 (at an edge of the bank the true delay may lie outside it).
/// An invalid snapshot (no update yet) has no flags.  Pure, no allocation.
int IntegratorDelaySnapshotFlags(const IntegratorDelaySnapshot& snapshot,
                                 const OnlineIntegratorDelayOptions& options);
/// Which physical bound of a bank with these options an integrator-delay model breaks: A not
/// finite or <= 0, nk outside [min, max], or nk at an edge as in kFlagOutOfBounds.  The same rule
/// flags published models and keeps models from the state.  Pure, no allocation (it runs on every
/// snapshot).
enum class IntegratorDelayBoundsViolation : std::uint8_t {
  kNone,
  kArea,
  kOutsideBank,
  kAtBankEdge
};
IntegratorDelayBoundsViolation CheckIntegratorDelayBounds(
    double area_m2, int delay_samples, const OnlineIntegratorDelayOptions& options);
/// CheckIntegratorDelayBounds as a sentence for a log line (empty when inside); allocates.
std::string IntegratorDelayBoundsProblem(double area_m2, int delay_samples,
                                         const OnlineIntegratorDelayOptions& options);

/// Bank health beyond the per-estimator RlsHealth.
struct IntegratorDelayBankHealth {
  bool closed_loop = false;                ///< the reported bank is the IV (closed-loop) one
  bool closed_loop_decided = false;        ///< kAuto has decided (always true for kOn and kOff)
  double outflow_level_correlation = 0.0;  ///< kAuto: ClosedLoopDetector's r (at the decision)
  bool outflow_moves = false;              ///< kAuto: ClosedLoopDetector::OutflowMoves()
  std::int64_t samples = 0;                ///< samples accepted into the time base
  std::int64_t bad_flow_samples = 0;       ///< flows replaced by the last good ones
  std::int64_t bad_level_samples = 0;      ///< no regression update on these samples
  std::int64_t dropped_samples = 0;        ///< bad flows before any good one: not used at all
  int switches = 0;                        ///< delay changes made by the selector
};

/// Online integrator-delay (ID) identification of a canal pool with a bank over the delay nk.
/// For the samples k = 0, 1, ... of inflow q_in (m^3/s), outflow q_out (m^3/s) and level y (m):
///   v_nk(k) = q_in(k - nk) - q_out(k - 1),   Q_nk(k) = sum_{j=k0..k} v_nk(j)  (m^3/s x samples),
///   y(k) = b Q_nk(k) + c + d (k - k0),       k0 = max_delay_samples + 1,
/// or, with wave_front_term, y(k) = b Q_nk(k) + p21 q_in(k - nk) + c + d (k - k0) (Rls<4>, the
/// batch FitIntegratorDelay's open-loop regression),
/// i.e. the level against the integrated total flow with an offset and a drift (the low-frequency
/// form of y(k) - y(k-1) = b (q_in(k - nk) - q_out(k - 1))), fitted by one Rls<3> per candidate
/// from k = k0 on (one IvRls per candidate in closed loop, see
/// OnlineIntegratorDelayOptions::closed_loop). With lambda = 1 and a large P0 each candidate equals
/// batch least squares on the rows phi = [Q_nk(k), 1, k - k0], k = k0..K.  area_m2 = Ts / b,
/// delay_s = nk Ts.
///
/// Forgetting < 1: Q_nk and k - k0 grow without bound while the memory does not, so the
/// regressor is re-centred every recentre_samples: internally phi = [Q - Q_c, 1, (k - k0) - t_c]
/// and theta = [b, c + b Q_c + d t_c, d], changed exactly by Rls::Transform at each new centre;
/// snapshots always report c and d in the batch convention above.
///
/// A non-finite or absurd flow is replaced by the last good value of that flow (so the
/// integrators stay continuous) and counted; a bad level skips the regression update for that
/// sample.  The selector (BankSelector) picks nk by each candidate's least-squares loss (or, by
/// option, the weighted a-priori error with hysteresis).
/// Allocates only in the constructor; Update and the snapshots never allocate.  Deterministic.
/// Not thread-safe, its const members included (a snapshot copies a candidate into the
/// RlsBank's scratch estimator).
class OnlineIntegratorDelayBank final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineIntegratorDelayBank(const OnlineIntegratorDelayOptions& options);

  /// One sample.  Returns true when the candidates were updated (k >= k0 and a good level).
  bool Update(double q_in_m3s, double q_out_m3s, double level_m);

  /// The selected candidate (valid = false before the selector's first choice).
  IntegratorDelaySnapshot Snapshot() const;
  /// Candidate with delay nk.  @pre min_delay_samples <= nk <= max_delay_samples.
  IntegratorDelaySnapshot CandidateSnapshot(int delay_samples) const;
  int selected_delay_samples() const;
  int num_candidates() const { return options_.max_delay_samples - options_.min_delay_samples + 1; }
  const IntegratorDelayBankHealth& health() const { return health_; }
  const OnlineIntegratorDelayOptions& options() const { return options_; }

 private:
  template <int N>
  void UpdateCandidates(RlsBank<N>& estimators, double t, double level_m);
  template <int N>
  void UpdateIvCandidates(std::vector<IvRls<N>>& estimators, double t, double level_m);
  template <int N>
  static Eigen::Matrix<double, N, N> CentreShift(double dq, double dt);
  /// theta with p21 >= 0 (wave_front_non_negative): theta itself, or the estimate constrained
  /// to p21 = 0 through the gain g (P or the IV gain).
  template <int N>
  Eigen::Matrix<double, N, 1> Constrained(const Eigen::Matrix<double, N, 1>& theta,
                                          const Eigen::Matrix<double, N, N>& g) const;
  void Recentre();
  void Decide();
  void FillThreeStepSnapshot(const OnlineThreeStep& t, IntegratorDelaySnapshot& s) const;
  template <int N, typename Estimator>
  void FillSnapshot(const Estimator& rls, std::size_t ui, IntegratorDelaySnapshot& s) const;
  template <int N>
  static void FillConditioning(const Eigen::Matrix<double, N, N>& p, IntegratorDelaySnapshot& s);
  const BankSelector& reported_selector() const {
    return health_.closed_loop ? iv_selector_ : selector_;
  }

  OnlineIntegratorDelayOptions options_;
  // The least-squares candidates, side by side (RlsBank: one update for all).
  std::optional<RlsBank<3>> estimators_;       // without the wave-front term
  std::optional<RlsBank<4>> wave_estimators_;  // with it
  std::vector<double> constrained_error_;      // kPredictionError with p21 >= 0: per candidate
  std::vector<char> constrained_;
  std::vector<IvRls<3>> iv_estimators_;       // closed loop, without the wave-front term
  std::vector<IvRls<4>> iv_wave_estimators_;  // closed loop, with it
  std::vector<OnlineThreeStep> three_step_;   // closed loop, three-step method
  std::vector<double> q_integrated_;          // Q_nk(k)
  std::vector<double> q_centre_;              // Q_c per candidate
  std::vector<double> qin_integrated_;        // instrument Qin_nk(k)
  std::vector<double> qin_centre_;            // its centre
  BankSelector selector_;                     // least-squares bank
  BankSelector iv_selector_;                  // IV bank
  ClosedLoopDetector detector_;
  bool ls_active_ = true;
  bool iv_active_ = false;
  bool three_step_active_ = false;
  double q_ref_ = 0.0;
  LagLine q_in_history_;  // lag nk: the inflow nk samples ago
  double q_in_good_ = 0.0;
  double q_out_good_ = 0.0;
  double q_out_previous_ = 0.0;
  bool have_good_ = false;
  std::int64_t k_ = -1;
  std::int64_t k0_ = 0;
  double t_centre_ = 0.0;
  int recentre_period_ = 0;
  IntegratorDelayBankHealth health_;
};

}  // namespace canalid::core
