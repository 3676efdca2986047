#include "core/online/online_integrator_delay.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numerics/lane_vectors.h"
#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineIntegratorDelayOptions", name, value, range);
}

/// IntegratorDelaySnapshot::flow_level_rms_m from b, P_bb (the covariance's b entry over sigma2)
/// and the estimator's updates.
double FlowLevelRms(double b, double p_bb, std::int64_t updates, double forgetting) {
  if (!(p_bb > 0.0 && std::isfinite(p_bb)) || updates <= 0) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double memory = static_cast<double>(updates);
  if (forgetting < 1.0) memory = std::min(memory, 1.0 / (1.0 - forgetting));
  return std::abs(b) / std::sqrt(p_bb * memory);
}

/// sum[i] += x[i] - c for i < n (the sum of (x - c), as Eigen's `sum += x - c` rounds it), two
/// pairs a step.
void AddDifference(const double* x, double c, double* sum, int n) {
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    StorePair(sum + i, LoadPair(sum + i) + (LoadPair(x + i) - c));
    StorePair(sum + i + 2, LoadPair(sum + i + 2) + (LoadPair(x + i + 2) - c));
  }
  for (; i < n; ++i) sum[i] += x[i] - c;
}

}  // namespace

void IntegratorDelayHealthOptions::Validate() const {
  if (!(condition_max > 1.0)) Fail("health.condition_max", condition_max, "> 1");
  if (!(information_min_per_p0 >= 0.0 && std::isfinite(information_min_per_p0))) {
    Fail("health.information_min_per_p0", information_min_per_p0, "finite, >= 0");
  }
  if (!(information_min_floor >= 0.0 && std::isfinite(information_min_floor))) {
    Fail("health.information_min_floor", information_min_floor, "finite, >= 0");
  }
  if (!(level_resolution_m >= 0.0 && std::isfinite(level_resolution_m))) {
    Fail("health.level_resolution_m", level_resolution_m, "finite, >= 0");
  }
}

int IntegratorDelaySnapshotFlags(const IntegratorDelaySnapshot& s,
                                 const OnlineIntegratorDelayOptions& options) {
  if (!s.valid) return 0;
  int flags = 0;
  if (!std::isfinite(s.b) || !std::isfinite(s.c_m) || !std::isfinite(s.d_m) ||
      !std::isfinite(s.area_m2) || !std::isfinite(s.health.trace_p)) {
    flags |= kFlagNan;
  }
  if (s.health.wound_up) flags |= kFlagWindup;
  if (!(s.information_min >= options.health.InformationMin(options.rls.initial_covariance)) ||
      s.flow_level_rms_m < options.health.level_resolution_m) {
    flags |= kFlagLowExcitation;
  }
  if (!(s.condition_number <= options.health.condition_max)) flags |= kFlagIllConditioned;
  if (s.health.frozen) flags |= kFlagFrozen;
  if (CheckIntegratorDelayBounds(s.area_m2, s.delay_samples, options) !=
      IntegratorDelayBoundsViolation::kNone) {
    flags |= kFlagOutOfBounds;
  }
  return flags;
}

IntegratorDelayBoundsViolation CheckIntegratorDelayBounds(double area_m2, int delay_samples,
                                                          const OnlineIntegratorDelayOptions& o) {
  if (!(area_m2 > 0.0 && std::isfinite(area_m2))) return IntegratorDelayBoundsViolation::kArea;
  if (delay_samples < o.min_delay_samples || delay_samples > o.max_delay_samples) {
    return IntegratorDelayBoundsViolation::kOutsideBank;
  }
  if (delay_samples == o.max_delay_samples ||
      (delay_samples == o.min_delay_samples && o.min_delay_samples > 0)) {
    return IntegratorDelayBoundsViolation::kAtBankEdge;
  }
  return IntegratorDelayBoundsViolation::kNone;
}

std::string IntegratorDelayBoundsProblem(double area_m2, int delay_samples,
                                         const OnlineIntegratorDelayOptions& o) {
  std::ostringstream m;
  switch (CheckIntegratorDelayBounds(area_m2, delay_samples, o)) {
    case IntegratorDelayBoundsViolation::kNone:
      break;
    case IntegratorDelayBoundsViolation::kArea:
      m << "area_m2 " << area_m2 << " is not > 0 and finite";
      break;
    case IntegratorDelayBoundsViolation::kOutsideBank:
      m << "delay " << delay_samples << " samples is outside the bank [" << o.min_delay_samples
        << ", " << o.max_delay_samples << "]";
      break;
    case IntegratorDelayBoundsViolation::kAtBankEdge:
      m << "delay " << delay_samples << " samples is at the edge of the bank ["
        << o.min_delay_samples << ", " << o.max_delay_samples
        << "]: the true delay may lie outside it";
      break;
  }
  return m.str();
}

void OnlineIntegratorDelayOptions::Validate() const {
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    Fail("sample_time_s", sample_time_s, "finite, > 0");
  }
  if (min_delay_samples < 0) Fail("min_delay_samples", min_delay_samples, ">= 0");
  if (max_delay_samples < min_delay_samples || max_delay_samples > 100000) {
    Fail("max_delay_samples", max_delay_samples, "min_delay_samples..100000");
  }
  if (!(flow_abs_max_m3s > 0.0)) Fail("flow_abs_max_m3s", flow_abs_max_m3s, "> 0");
  if (!(level_abs_max_m > 0.0)) Fail("level_abs_max_m", level_abs_max_m, "> 0");
  if (closed_loop_window_samples < 3 || closed_loop_window_samples > 1000000000) {
    Fail("closed_loop_window_samples", closed_loop_window_samples, "3..1e9");
  }
  if (!(outflow_direct_gain_s_per_m2 >= 0.0 && outflow_direct_gain_s_per_m2 <= 10.0)) {
    Fail("outflow_direct_gain_s_per_m2", outflow_direct_gain_s_per_m2, "0..10");
  }
  rls.Validate(wave_front_term ? 4 : 3);
  if (idz_level_equation && !wave_front_term) {
    throw std::invalid_argument("idz_level_equation needs wave_front_term");
  }
  selector.Validate();
  health.Validate();
  if (closed_loop == ClosedLoopMode::kThreeStep) three_step.Validate();
}

OnlineIntegratorDelayBank::OnlineIntegratorDelayBank(const OnlineIntegratorDelayOptions& options)
    : options_(options),
      selector_((options.Validate(), options.max_delay_samples - options.min_delay_samples + 1),
                SelectorOptionsFor(options.selector, IsLeastSquaresMethod(options.rls.method))),
      iv_selector_(options.max_delay_samples - options.min_delay_samples + 1,
                   // An IV estimate does not minimise its residuals.
                   SelectorOptionsFor(options.selector, false)),
      q_in_history_(options.max_delay_samples + 1) {
  const int n = options_.max_delay_samples - options_.min_delay_samples + 1;
  const auto un = static_cast<std::size_t>(n);
  three_step_active_ = options_.closed_loop == ClosedLoopMode::kThreeStep;
  // kThreeStep runs the IV bank for its delay choice (OnlineIntegratorDelayOptions::closed_loop).
  ls_active_ =
      options_.closed_loop == ClosedLoopMode::kOff || options_.closed_loop == ClosedLoopMode::kAuto;
  iv_active_ = options_.closed_loop != ClosedLoopMode::kOff;
  health_.closed_loop = options_.closed_loop == ClosedLoopMode::kOn || three_step_active_;
  health_.closed_loop_decided = options_.closed_loop != ClosedLoopMode::kAuto;
  // The offset's regressor, 1, is set once (UpdateCandidates writes the other rows).
  if (ls_active_ && options_.wave_front_term) {
    wave_estimators_.emplace(options_.rls, n);
    wave_estimators_->regressors().row(2).head(n).setOnes();
  }
  if (ls_active_ && !options_.wave_front_term) {
    estimators_.emplace(options_.rls, n);
    estimators_->regressors().row(1).head(n).setOnes();
  }
  constrained_error_.assign(un, 0.0);
  constrained_.assign(un, 0);
  if (iv_active_ && options_.wave_front_term) {
    iv_wave_estimators_.assign(un, IvRls<4>(options_.rls));
  }
  if (iv_active_ && !options_.wave_front_term) iv_estimators_.assign(un, IvRls<3>(options_.rls));
  q_integrated_.assign(un, 0.0);
  q_centre_.assign(un, 0.0);
  qin_integrated_.assign(un, 0.0);
  qin_centre_.assign(un, 0.0);
  k0_ = options_.max_delay_samples + 1;
  const double lambda = options_.rls.forgetting;
  if (options_.recentre_samples > 0) {
    recentre_period_ = options_.recentre_samples;
  } else if (options_.recentre_samples == 0 && lambda < 1.0) {
    recentre_period_ = static_cast<int>(std::ceil(1.0 / (1.0 - lambda)));
  }
  if (three_step_active_) {
    ThreeStepOptions t = options_.three_step;
    t.regression = options_.rls;
    t.regression.lower.resize(0);
    t.regression.upper.resize(0);
    t.sensitivity.forgetting = lambda;
    t.recentre_samples = recentre_period_;
    three_step_.assign(un, OnlineThreeStep(t));
  }
}

bool OnlineIntegratorDelayBank::Update(double q_in_m3s, double q_out_m3s, double level_m) {
  const double flow_max = options_.flow_abs_max_m3s;
  const bool in_ok = FiniteWithin(q_in_m3s, flow_max);
  const bool out_ok = FiniteWithin(q_out_m3s, flow_max);
  if (!have_good_ && !(in_ok && out_ok)) {
    ++health_.dropped_samples;
    return false;
  }
  if (!in_ok || !out_ok) ++health_.bad_flow_samples;
  if (!have_good_) q_ref_ = q_in_m3s;
  if (in_ok) q_in_good_ = q_in_m3s;
  if (out_ok) q_out_good_ = q_out_m3s;
  have_good_ = true;
  ++k_;
  ++health_.samples;
  q_in_history_.Push(q_in_good_);
  const bool deciding = !health_.closed_loop_decided;
  if (deciding) detector_.AddInflow(q_in_good_);
  bool updated = false;
  if (k_ >= k0_) {
    const double t = static_cast<double>(k_ - k0_);
    if (recentre_period_ > 0 && t - t_centre_ >= recentre_period_) Recentre();
    // The candidates' delayed inflows q_in(k - nk), nk = min..max, side by side.
    const double* delayed_inflow = q_in_history_.Lags() + options_.min_delay_samples;
    AddDifference(delayed_inflow, q_out_previous_, q_integrated_.data(), num_candidates());
    if (iv_active_) {  // the instrument; once the IV bank stops it is never read again
      AddDifference(delayed_inflow, q_ref_, qin_integrated_.data(), num_candidates());
    }
    const bool level_ok = FiniteWithin(level_m, options_.level_abs_max_m);
    if (!level_ok) ++health_.bad_level_samples;
    const double y_fit = level_m + options_.outflow_direct_gain_s_per_m2 * q_out_good_;
    if (three_step_active_) {
      // Runs on bad levels too: its flow integrators must stay continuous.
      for (int i = 0; i < num_candidates(); ++i) {
        const double u = delayed_inflow[i];
        three_step_[static_cast<std::size_t>(i)].Update(u, u - q_out_previous_, y_fit, level_ok);
      }
    }
    if (level_ok) {
      const double y = y_fit;
      if (ls_active_ && options_.wave_front_term) UpdateCandidates(*wave_estimators_, t, y);
      if (ls_active_ && !options_.wave_front_term) UpdateCandidates(*estimators_, t, y);
      if (iv_active_ && options_.wave_front_term) UpdateIvCandidates(iv_wave_estimators_, t, y);
      if (iv_active_ && !options_.wave_front_term) UpdateIvCandidates(iv_estimators_, t, y);
      if (ls_active_) selector_.Commit();
      if (iv_active_) iv_selector_.Commit();
      updated = true;
      if (deciding) {
        detector_.AddOutflowLevel(q_out_good_, level_m);
        if (detector_.samples() >= options_.closed_loop_window_samples) Decide();
      }
    }
  }
  health_.switches = reported_selector().switches();
  q_out_previous_ = q_out_good_;
  return updated;
}

void OnlineIntegratorDelayBank::Decide() {
  health_.closed_loop_decided = true;
  health_.outflow_level_correlation = detector_.OutflowLevelCorrelation();
  health_.outflow_moves = detector_.OutflowMoves();
  health_.closed_loop = detector_.ClosedLoop();
  // The losing bank stops; its estimators keep their memory but are never read again.
  ls_active_ = !health_.closed_loop;
  iv_active_ = health_.closed_loop;
}

template <int N>
void OnlineIntegratorDelayBank::UpdateIvCandidates(std::vector<IvRls<N>>& estimators, double t,
                                                   double level_m) {
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const int nk = options_.min_delay_samples + i;
    Eigen::Matrix<double, N, 1> phi;
    Eigen::Matrix<double, N, 1> z;
    const double tc = t - t_centre_;
    const double qin = qin_integrated_[ui] - qin_centre_[ui];
    if constexpr (N == 4) {
      const double volume = q_integrated_[ui] - q_centre_[ui];
      phi << (options_.idz_level_equation ? volume - q_in_history_[nk] : volume), q_in_history_[nk],
          1.0, tc;
      z << qin, q_in_history_[nk], 1.0, tc;
    } else {
      phi << q_integrated_[ui] - q_centre_[ui], 1.0, tc;
      z << qin, 1.0, tc;
    }
    double constrained_error = 0.0;
    const bool constrained =
        N == 4 && options_.wave_front_non_negative && estimators[ui].theta()(1) < 0.0;
    if (constrained) {
      constrained_error =
          level_m - phi.dot(Constrained<N>(estimators[ui].theta(), estimators[ui].gain_matrix()));
    }
    const auto result = estimators[ui].Update(phi, z, level_m);
    // The selector sees the error of the estimate the snapshot reports (p21 >= 0).
    iv_selector_.Record(i, constrained && std::isfinite(result.prediction_error)
                               ? constrained_error
                               : result.prediction_error);
  }
}

template <int N>
void OnlineIntegratorDelayBank::UpdateCandidates(RlsBank<N>& estimators, double t, double level_m) {
  // The regressors: row r of phi holds regressor r of every candidate (the offset's, 1, is set
  // in the constructor), written two candidates at a time.
  typename RlsBank<N>::Regressors& phi = estimators.regressors();
  const int n = num_candidates();
  double* volume = phi.row(0).data();  // each row is contiguous (RowMajor)
  double* wave_front = N == 4 ? phi.row(1).data() : nullptr;
  double* drift = phi.row(N - 1).data();
  const double* q = q_integrated_.data();
  const double* centre = q_centre_.data();
  const double* delayed = q_in_history_.Lags() + options_.min_delay_samples;
  const bool idz = N == 4 && options_.idz_level_equation;
  const double tc = t - t_centre_;
  const DoublePair tc2 = DoublePair{} + tc;
  int c = 0;
  for (; c + 2 <= n; c += 2) {
    DoublePair v = LoadPair(q + c) - LoadPair(centre + c);
    if constexpr (N == 4) {
      const DoublePair u = LoadPair(delayed + c);
      StorePair(wave_front + c, u);
      if (idz) v -= u;
    }
    StorePair(volume + c, v);
    StorePair(drift + c, tc2);
  }
  if (c < n) {
    double v = q[c] - centre[c];
    if constexpr (N == 4) {
      wave_front[c] = delayed[c];
      if (idz) v -= delayed[c];
    }
    volume[c] = v;
    drift[c] = tc;
  }
  if (selector_.criterion() == BankCriterion::kResidual) {
    // The snapshot reports the p21 = 0 fit when p21 < 0 (wave_front_non_negative): its loss is
    // that of the equality-constrained least squares.
    estimators.UpdateWithLosses(level_m, N == 4 && options_.wave_front_non_negative ? 1 : -1,
                                selector_.LossSlots());
    return;
  }
  // The selector sees the error of the estimate the snapshot reports (p21 >= 0): for a candidate
  // whose p21 is negative, that of the constrained estimate before the update.
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    constrained_[ui] = N == 4 && options_.wave_front_non_negative && estimators.theta(i, 1) < 0.0;
    if (constrained_[ui] != 0) {
      const Rls<N>& rls = estimators.Lane(i);
      Eigen::Matrix<double, N, N> p;
      rls.Covariance(p);
      const Eigen::Matrix<double, N, 1> phi_i = phi.col(i);
      constrained_error_[ui] = level_m - phi_i.dot(Constrained<N>(rls.theta(), p));
    }
  }
  estimators.Update(level_m);
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const double error = estimators.result(i).prediction_error;
    selector_.Record(
        i, constrained_[ui] != 0 && std::isfinite(error) ? constrained_error_[ui] : error);
  }
}

template <int N>
Eigen::Matrix<double, N, 1> OnlineIntegratorDelayBank::Constrained(
    const Eigen::Matrix<double, N, 1>& theta, const Eigen::Matrix<double, N, N>& g) const {
  if constexpr (N == 4) {
    // The p21 = 0 solution of the same normal (or instrument) equations: theta - g e2 p21 / g22.
    if (options_.wave_front_non_negative && theta(1) < 0.0 && g(1, 1) > 0.0) {
      Eigen::Matrix<double, N, 1> c = theta - g.col(1) * (theta(1) / g(1, 1));
      c(1) = 0.0;
      return c;
    }
  }
  return theta;
}

template <int N>
Eigen::Matrix<double, N, N> OnlineIntegratorDelayBank::CentreShift(double dq, double dt) {
  // The offset is the second-last parameter and the drift the last, with or without p21; the
  // wave-front regressor q_in(k - nk) is bounded and needs no centre.
  constexpr int kOffset = N - 2;
  Eigen::Matrix<double, N, N> transform = Eigen::Matrix<double, N, N>::Identity();
  transform(kOffset, 0) = dq;
  transform(kOffset, N - 1) = dt;
  return transform;
}

void OnlineIntegratorDelayBank::Recentre() {
  // New centre at the current sample.  c' = c + b Q_c + d t_c, so moving the centre by
  // (dQ, dt) maps theta by an exact linear T; the fit itself is unchanged.  The instrument is
  // re-centred the same way (S, with dQin), which leaves the IV estimate unchanged too.
  const double t_new = static_cast<double>(k_ - k0_);
  const double dt = t_new - t_centre_;
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const double dq = q_integrated_[ui] - q_centre_[ui];
    const double dqin = qin_integrated_[ui] - qin_centre_[ui];
    if (ls_active_ && options_.wave_front_term)
      wave_estimators_->Transform(i, CentreShift<4>(dq, dt));
    if (ls_active_ && !options_.wave_front_term) estimators_->Transform(i, CentreShift<3>(dq, dt));
    if (iv_active_ && options_.wave_front_term) {
      iv_wave_estimators_[ui].Transform(CentreShift<4>(dq, dt), CentreShift<4>(dqin, dt));
    }
    if (iv_active_ && !options_.wave_front_term) {
      iv_estimators_[ui].Transform(CentreShift<3>(dq, dt), CentreShift<3>(dqin, dt));
    }
    q_centre_[ui] = q_integrated_[ui];
    qin_centre_[ui] = qin_integrated_[ui];
  }
  t_centre_ = t_new;
}

int OnlineIntegratorDelayBank::selected_delay_samples() const {
  const int s = reported_selector().selected();
  return s < 0 ? -1 : options_.min_delay_samples + s;
}

IntegratorDelaySnapshot OnlineIntegratorDelayBank::Snapshot() const {
  const int nk = selected_delay_samples();
  if (nk < 0) return IntegratorDelaySnapshot{};
  return CandidateSnapshot(nk);
}

IntegratorDelaySnapshot OnlineIntegratorDelayBank::CandidateSnapshot(int delay_samples) const {
  IntegratorDelaySnapshot s;
  const int i = delay_samples - options_.min_delay_samples;
  if (i < 0 || i >= num_candidates()) return s;
  const auto ui = static_cast<std::size_t>(i);
  s.sample = k_;
  s.delay_samples = delay_samples;
  s.delay_s = delay_samples * options_.sample_time_s;
  if (three_step_active_) {
    FillThreeStepSnapshot(three_step_[ui], s);
  } else if (health_.closed_loop) {
    if (options_.wave_front_term) {
      FillSnapshot<4>(iv_wave_estimators_[ui], ui, s);
    } else {
      FillSnapshot<3>(iv_estimators_[ui], ui, s);
    }
  } else if (options_.wave_front_term) {
    FillSnapshot<4>(wave_estimators_->Lane(i), ui, s);
  } else {
    FillSnapshot<3>(estimators_->Lane(i), ui, s);
  }
  s.loss = reported_selector().loss(i);
  s.flags = IntegratorDelaySnapshotFlags(s, options_);
  return s;
}

void OnlineIntegratorDelayBank::FillThreeStepSnapshot(const OnlineThreeStep& t,
                                                      IntegratorDelaySnapshot& s) const {
  const auto& rls = t.regression();
  s.valid = rls.health().updates > 0;
  s.b = t.b();
  s.wave_front_gain_s_per_m2 = 0.0;
  s.c_m = t.c_m();
  s.d_m = t.d_m();
  s.area_m2 = options_.sample_time_s / s.b;
  t.StandardDeviations(s.b_std, s.c_std_m, s.d_std_m);
  s.area_std_m2 = options_.sample_time_s * s.b_std / (s.b * s.b);
  s.prediction_error_m = rls.last_prediction_error();
  s.innovation_std_m = std::sqrt(rls.innovation_variance());
  s.health = rls.health();
  // Step 3's b is a regression coefficient too; its P_bb is b_std^2 / sigma2.
  const double s2 = rls.innovation_variance();
  s.flow_level_rms_m = FlowLevelRms(s.b, s2 > 0.0 ? s.b_std * s.b_std / s2 : 0.0, s.health.updates,
                                    options_.rls.forgetting);
  Eigen::Matrix<double, OnlineThreeStep::kParams, OnlineThreeStep::kParams> p;
  rls.Covariance(p);
  FillConditioning<OnlineThreeStep::kParams>(p, s);
}

template <int N>
void OnlineIntegratorDelayBank::FillConditioning(const Eigen::Matrix<double, N, N>& p,
                                                 IntegratorDelaySnapshot& s) {
  // Fixed size: the solver lives on the stack, nothing is allocated.
  if (!p.allFinite()) {
    s.condition_number = std::numeric_limits<double>::infinity();
    s.information_min = 0.0;
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(p, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()(0);
  const double hi = eig.eigenvalues()(N - 1);
  s.condition_number = lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
  s.information_min = hi > 0.0 ? 1.0 / hi : 0.0;
}

template <int N, typename Estimator>
void OnlineIntegratorDelayBank::FillSnapshot(const Estimator& rls, std::size_t ui,
                                             IntegratorDelaySnapshot& s) const {
  constexpr int kOffset = N - 2;
  constexpr int kDrift = N - 1;
  s.valid = rls.health().updates > 0;
  Eigen::Matrix<double, N, N> p;
  rls.Covariance(p);
  Eigen::Matrix<double, N, 1> th = rls.theta();
  if constexpr (N == 4) {
    if (options_.wave_front_non_negative && th(1) < 0.0) {
      // The constrained estimate and its covariance P - P e2 e2' P / P22 (for the IV bank the
      // gain's constraint, with the unconstrained covariance's P22 rows removed likewise).
      Eigen::Matrix<double, N, N> g;
      if constexpr (requires { rls.gain_matrix(); }) {
        g = rls.gain_matrix();
      } else {
        g = p;
      }
      th = Constrained<N>(th, g);
      if (p(1, 1) > 0.0) p -= p.col(1) * p.row(1) / p(1, 1);
    }
  }
  const double qc = q_centre_[ui];
  s.b = th(0);
  if constexpr (N == 4) s.wave_front_gain_s_per_m2 = th(1);
  s.d_m = th(kDrift);
  s.c_m = th(kOffset) - th(0) * qc - th(kDrift) * t_centre_;
  s.area_m2 = options_.sample_time_s / s.b;
  const double s2 = rls.innovation_variance();
  Eigen::Matrix<double, N, 1> a = Eigen::Matrix<double, N, 1>::Zero();  // c = a' theta
  a(0) = -qc;
  a(kOffset) = 1.0;
  a(kDrift) = -t_centre_;
  s.b_std = std::sqrt(std::max(0.0, s2 * p(0, 0)));
  s.d_std_m = std::sqrt(std::max(0.0, s2 * p(kDrift, kDrift)));
  s.c_std_m = std::sqrt(std::max(0.0, s2 * a.dot(p * a)));
  s.area_std_m2 = options_.sample_time_s * s.b_std / (s.b * s.b);
  s.prediction_error_m = rls.last_prediction_error();
  s.innovation_std_m = std::sqrt(s2);
  s.health = rls.health();
  s.flow_level_rms_m = FlowLevelRms(s.b, p(0, 0), s.health.updates, options_.rls.forgetting);
  FillConditioning<N>(p, s);
}

}  // namespace canalid::core
