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
      y_history_(std::max(options.na, 1)) {
  candidates_ = ArxCandidates::Make(options_.rls, n_,
                                    options_.max_delay_samples - options_.min_delay_samples + 1);
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
    for (int i = 0; i < options_.na; ++i) {
      minus_y_lags_[static_cast<std::size_t>(i)] = -y_history_[i];
    }
    const ArxRows rows{.na = options_.na,
                       .nb = options_.nb,
                       .min_delay = options_.min_delay_samples,
                       .minus_y_lags = minus_y_lags_.data(),
                       .u = &u_history_,
                       .u_bad = &u_bad_history_};
    candidates_->Update(rows, y, selector_);
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
  if (c < 0 || c >= selector_.num_candidates()) return s;
  ArxCandidateState state;
  candidates_->State(c, state);
  s.valid = state.health.updates > 0;
  s.sample = k_;
  s.delay_samples = delay_samples;
  const int na = options_.na;
  const int nb = options_.nb;
  s.a = state.theta.head(na);
  s.b = state.theta.segment(na, nb);
  s.a_std = state.std_dev.head(na);
  s.b_std = state.std_dev.segment(na, nb);
  s.prediction_error = state.last_prediction_error;
  s.innovation_std = std::sqrt(state.innovation_variance);
  s.loss = selector_.loss(c);
  s.health = state.health;
  return s;
}

}  // namespace canalid::core
