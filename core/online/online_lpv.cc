#include "core/online/online_lpv.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineLpvArxOptions", name, value, range);
}

}  // namespace

void OnlineLpvArxOptions::Validate() const {
  CheckOnlineArxOrders("OnlineLpvArxOptions", na, nb);
  if (delay_samples < 0) Fail("delay_samples", delay_samples, ">= 0");
  if (!(input_abs_max > 0.0)) Fail("input_abs_max", input_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  if (!(scheduling_abs_max > 0.0)) Fail("scheduling_abs_max", scheduling_abs_max, "> 0");
  rls.Validate(3 * (na + nb));
}

OnlineLpvArx::OnlineLpvArx(const OnlineLpvArxOptions& options)
    : options_(options),
      rls_((options.Validate(), options.rls), 3 * (options.na + options.nb)),
      u_history_(options.delay_samples + options.nb),
      y_history_(std::max(options.na, 1)),
      phi_(Eigen::VectorXd::Zero(options.na + options.nb)),
      expanded_(Eigen::VectorXd::Zero(3 * Eigen::Index{options.na + options.nb})) {
  k_start_ = std::max(options_.na, options_.delay_samples + options_.nb - 1);
}

bool OnlineLpvArx::Update(double u, double y, double scheduling) {
  ++k_;
  if (!FiniteWithin(u, options_.input_abs_max)) {
    last_bad_u_ = k_;
    u = 0.0;  // never read by a regression
  }
  const bool y_ok = FiniteWithin(y, options_.output_abs_max);
  if (!y_ok) last_bad_y_ = k_;
  const bool s_ok = FiniteWithin(scheduling, options_.scheduling_abs_max);
  u_history_.Push(u);
  bool updated = false;
  const int nk = options_.delay_samples;
  const bool u_window_ok = !(k_ - nk - options_.nb + 1 <= last_bad_u_ && last_bad_u_ <= k_ - nk);
  if (k_ >= k_start_ && s_ok && k_ - last_bad_y_ > options_.na && u_window_ok) {
    for (int i = 0; i < options_.na; ++i) phi_(i) = -y_history_[i];
    for (int j = 0; j < options_.nb; ++j) phi_(options_.na + j) = u_history_[nk + j];
    LpvExpand(phi_, scheduling, expanded_);
    updated = rls_.Update(expanded_, y).outcome == RlsOutcome::kUpdated;
  }
  y_history_.Push(y_ok ? y : 0.0);
  return updated;
}

void OnlineLpvArx::ParametersAt(double s, ArxParamVector& a, ArxParamVector& b) const {
  const auto& th = rls_.theta();
  a.resize(options_.na);
  b.resize(options_.nb);
  for (int i = 0; i < options_.na + options_.nb; ++i) {
    const Eigen::Index j = 3 * Eigen::Index{i};
    const double p = th(j) + th(j + 1) * s + th(j + 2) * s * s;
    if (i < options_.na) {
      a(i) = p;
    } else {
      b(i - options_.na) = p;
    }
  }
}

}  // namespace canalid::core
