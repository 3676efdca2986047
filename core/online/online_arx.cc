#include "core/online/online_arx.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineArxOptions", name, value, range);
}

}  // namespace

void CheckOnlineArxOrders(std::string_view owner, int na, int nb) {
  if (na < 0) ThrowOptionOutOfRange(owner, "na", na, ">= 0");
  if (nb < 1) ThrowOptionOutOfRange(owner, "nb", nb, ">= 1");
  if (na + nb > kMaxOnlineArxParams) ThrowOptionOutOfRange(owner, "nb", nb, "na + nb <= 16");
}

void OnlineArxOptions::Validate() const {
  CheckOnlineArxOrders("OnlineArxOptions", na, nb);
  if (min_delay_samples < 0) Fail("min_delay_samples", min_delay_samples, ">= 0");
  if (max_delay_samples < min_delay_samples || max_delay_samples > 100000) {
    Fail("max_delay_samples", max_delay_samples, "min_delay_samples..100000");
  }
  if (!(input_abs_max > 0.0)) Fail("input_abs_max", input_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  rls.Validate(na + nb);
  selector.Validate();
}

OnlineArxBank::OnlineArxBank(const OnlineArxOptions& options)
    : options_(options),
      n_((options.Validate(), options.na + options.nb)),
      selector_(options.max_delay_samples - options.min_delay_samples + 1,
                SelectorOptionsFor(options.selector, IsLeastSquaresMethod(options.rls.method))),
      u_history_(options.max_delay_samples + options.nb),
      u_bad_history_(options.max_delay_samples + options.nb),
      y_history_(std::max(options.na, 1)),
      phi_(Eigen::VectorXd::Zero(options.na + options.nb)) {
  const int count = options_.max_delay_samples - options_.min_delay_samples + 1;
  estimators_.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) estimators_.emplace_back(options_.rls, n_);
  k_start_ = std::max(options_.na, options_.max_delay_samples + options_.nb - 1);
}

bool OnlineArxBank::Update(double u, double y) {
  ++k_;
  ++health_.samples;
  const bool u_ok = FiniteWithin(u, options_.input_abs_max);
  if (!u_ok) {
    ++health_.bad_inputs;
    u = 0.0;  // placeholder in the history; no regression reads it (u_bad_history_)
  }
  u_bad_history_.Push(u_ok ? 0 : 1);
  const bool y_ok = FiniteWithin(y, options_.output_abs_max);
  if (!y_ok) {
    ++health_.bad_outputs;
    last_bad_y_ = k_;
  }
  u_history_.Push(u);
  bool updated = false;
  // Rows that would contain a bad value: y(k) itself or y(k-na..k-1), u(k-nk-nb+1..k-nk).
  const bool y_window_ok = k_ - last_bad_y_ > options_.na;
  if (k_ >= k_start_ && y_window_ok) {
    for (int i = 0; i < options_.na; ++i) phi_(i) = -y_history_[i];
    for (int c = 0; c < static_cast<int>(estimators_.size()); ++c) {
      const int nk = options_.min_delay_samples + c;
      // Every input of the row must be good, not only the most recent bad one outside it.
      bool u_window_ok = true;
      for (int j = 0; j < options_.nb; ++j) {
        phi_(options_.na + j) = u_history_[nk + j];
        u_window_ok = u_window_ok && u_bad_history_[nk + j] == 0;
      }
      if (!u_window_ok) continue;
      Rls<Eigen::Dynamic>& rls = estimators_[static_cast<std::size_t>(c)];
      const auto result = rls.Update(phi_, y);
      if (selector_.criterion() == BankCriterion::kResidual) {
        selector_.SetLoss(c, rls.residual_sum_of_squares());
      } else {
        selector_.Record(c, result.prediction_error);
      }
    }
    selector_.Commit();
    updated = true;
  }
  y_history_.Push(y_ok ? y : 0.0);
  health_.switches = selector_.switches();
  return updated;
}

int OnlineArxBank::selected_delay_samples() const {
  const int s = selector_.selected();
  return s < 0 ? -1 : options_.min_delay_samples + s;
}

ArxSnapshot OnlineArxBank::Snapshot() const {
  const int nk = selected_delay_samples();
  if (nk < 0) return ArxSnapshot{};
  return CandidateSnapshot(nk);
}

ArxSnapshot OnlineArxBank::CandidateSnapshot(int delay_samples) const {
  ArxSnapshot s;
  const int c = delay_samples - options_.min_delay_samples;
  if (c < 0 || c >= static_cast<int>(estimators_.size())) return s;
  const Rls<Eigen::Dynamic>& rls = estimators_[static_cast<std::size_t>(c)];
  s.valid = rls.health().updates > 0;
  s.sample = k_;
  s.delay_samples = delay_samples;
  const int na = options_.na;
  const int nb = options_.nb;
  s.a = rls.theta().head(na);
  s.b = rls.theta().segment(na, nb);
  s.a_std.resize(na);
  s.b_std.resize(nb);
  const double s2 = rls.innovation_variance();
  for (int i = 0; i < na; ++i) s.a_std(i) = rls.StandardDeviation(i);
  for (int j = 0; j < nb; ++j) s.b_std(j) = rls.StandardDeviation(na + j);
  s.prediction_error = rls.last_prediction_error();
  s.innovation_std = std::sqrt(s2);
  s.loss = selector_.loss(c);
  s.health = rls.health();
  return s;
}

}  // namespace canalid::core
