#include "core/online_id.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  std::ostringstream m;
  m << "OnlineIdOptions." << name << " = " << value << " is out of range (allowed: " << range
    << ")";
  throw std::invalid_argument(m.str());
}

bool Good(double v, double bound) { return std::isfinite(v) && std::abs(v) <= bound; }

}  // namespace

void OnlineIdOptions::Validate() const {
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    Fail("sample_time_s", sample_time_s, "finite, > 0");
  }
  if (min_delay_samples < 0) Fail("min_delay_samples", min_delay_samples, ">= 0");
  if (max_delay_samples < min_delay_samples || max_delay_samples > 100000) {
    Fail("max_delay_samples", max_delay_samples, "min_delay_samples..100000");
  }
  if (!(flow_abs_max_m3s > 0.0)) Fail("flow_abs_max_m3s", flow_abs_max_m3s, "> 0");
  if (!(level_abs_max_m > 0.0)) Fail("level_abs_max_m", level_abs_max_m, "> 0");
  rls.Validate(3);
  selector.Validate();
}

OnlineIdBank::OnlineIdBank(const OnlineIdOptions& options)
    : options_(options),
      selector_((options.Validate(), options.max_delay_samples - options.min_delay_samples + 1),
                options.selector),
      q_in_history_(options.max_delay_samples + 1) {
  const int n = options_.max_delay_samples - options_.min_delay_samples + 1;
  for (int i = 0; i < n; ++i) {
    if (options_.closed_loop_iv) {
      iv_estimators_.emplace_back(options_.rls);
    } else {
      estimators_.emplace_back(options_.rls);
    }
  }
  q_integrated_.assign(static_cast<std::size_t>(n), 0.0);
  q_centre_.assign(static_cast<std::size_t>(n), 0.0);
  qin_integrated_.assign(static_cast<std::size_t>(n), 0.0);
  qin_centre_.assign(static_cast<std::size_t>(n), 0.0);
  k0_ = options_.max_delay_samples + 1;
  const double lambda = options_.rls.forgetting;
  if (options_.recentre_samples > 0) {
    recentre_period_ = options_.recentre_samples;
  } else if (options_.recentre_samples == 0 && lambda < 1.0) {
    recentre_period_ = static_cast<int>(std::ceil(1.0 / (1.0 - lambda)));
  }
}

bool OnlineIdBank::Update(double q_in_m3s, double q_out_m3s, double level_m) {
  const double flow_max = options_.flow_abs_max_m3s;
  const bool in_ok = Good(q_in_m3s, flow_max);
  const bool out_ok = Good(q_out_m3s, flow_max);
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
  bool updated = false;
  if (k_ >= k0_) {
    const double t = static_cast<double>(k_ - k0_);
    if (recentre_period_ > 0 && t - t_centre_ >= recentre_period_) Recentre();
    const bool level_ok = Good(level_m, options_.level_abs_max_m);
    if (!level_ok) ++health_.bad_level_samples;
    for (int i = 0; i < num_candidates(); ++i) {
      const auto ui = static_cast<std::size_t>(i);
      const int nk = options_.min_delay_samples + i;
      q_integrated_[ui] += q_in_history_[nk] - q_out_previous_;
      qin_integrated_[ui] += q_in_history_[nk] - q_ref_;
      if (!level_ok) continue;
      const Eigen::Vector3d phi(q_integrated_[ui] - q_centre_[ui], 1.0, t - t_centre_);
      double error = 0.0;
      if (options_.closed_loop_iv) {
        const Eigen::Vector3d z(qin_integrated_[ui] - qin_centre_[ui], 1.0, t - t_centre_);
        error = iv_estimators_[ui].Update(phi, z, level_m).prediction_error;
      } else {
        error = estimators_[ui].Update(phi, level_m).prediction_error;
      }
      selector_.Record(i, error);
    }
    if (level_ok) {
      selector_.Commit();
      updated = true;
    }
  }
  health_.switches = selector_.switches();
  q_out_previous_ = q_out_good_;
  return updated;
}

void OnlineIdBank::Recentre() {
  // New centre at the current sample.  c' = c + b Q_c + d t_c, so moving the centre by
  // (dQ, dt) maps theta by the exact linear T below; the fit itself is unchanged.
  const double t_new = static_cast<double>(k_ - k0_);
  const double dt = t_new - t_centre_;
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const double dq = q_integrated_[ui] - q_centre_[ui];
    Eigen::Matrix3d transform = Eigen::Matrix3d::Identity();
    transform(1, 0) = dq;
    transform(1, 2) = dt;
    if (options_.closed_loop_iv) {
      Eigen::Matrix3d instrument = Eigen::Matrix3d::Identity();
      instrument(1, 0) = qin_integrated_[ui] - qin_centre_[ui];
      instrument(1, 2) = dt;
      iv_estimators_[ui].Transform(transform, instrument);
      qin_centre_[ui] = qin_integrated_[ui];
    } else {
      estimators_[ui].Transform(transform);
    }
    q_centre_[ui] = q_integrated_[ui];
  }
  t_centre_ = t_new;
}

int OnlineIdBank::selected_delay_samples() const {
  const int s = selector_.selected();
  return s < 0 ? -1 : options_.min_delay_samples + s;
}

IdSnapshot OnlineIdBank::Snapshot() const {
  const int nk = selected_delay_samples();
  if (nk < 0) return IdSnapshot{};
  return CandidateSnapshot(nk);
}

IdSnapshot OnlineIdBank::CandidateSnapshot(int delay_samples) const {
  const int i = delay_samples - options_.min_delay_samples;
  if (i < 0 || i >= num_candidates()) return IdSnapshot{};
  const auto ui = static_cast<std::size_t>(i);
  return options_.closed_loop_iv ? MakeSnapshot(iv_estimators_[ui], i)
                                 : MakeSnapshot(estimators_[ui], i);
}

template <typename Estimator>
IdSnapshot OnlineIdBank::MakeSnapshot(const Estimator& rls, int i) const {
  IdSnapshot s;
  const auto ui = static_cast<std::size_t>(i);
  const int delay_samples = options_.min_delay_samples + i;
  const RlsHealth health = rls.health();
  s.valid = health.updates > 0;
  s.sample = k_;
  s.delay_samples = delay_samples;
  s.delay_s = delay_samples * options_.sample_time_s;
  const Eigen::Vector3d& th = rls.theta();
  const double qc = q_centre_[ui];
  s.b = th(0);
  s.d_m = th(2);
  s.c_m = th(1) - th(0) * qc - th(2) * t_centre_;
  s.area_m2 = options_.sample_time_s / s.b;
  Eigen::Matrix3d p;
  rls.Covariance(p);
  const double s2 = rls.innovation_variance();
  const Eigen::Vector3d a(-qc, 1.0, -t_centre_);  // c = a' theta
  s.b_std = std::sqrt(std::abs(s2 * p(0, 0)));
  s.d_std_m = std::sqrt(std::abs(s2 * p(2, 2)));
  s.c_std_m = std::sqrt(std::abs(s2 * a.dot(p * a)));
  s.area_std_m2 = options_.sample_time_s * s.b_std / (s.b * s.b);
  s.prediction_error_m = rls.last_prediction_error();
  s.innovation_std_m = std::sqrt(s2);
  s.loss = selector_.loss(i);
  s.health = health;
  return s;
}

}  // namespace canalid::core
