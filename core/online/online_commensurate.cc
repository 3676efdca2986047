#include "core/online/online_commensurate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineCommensurateOptions", name, value, range);
}

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

void OnlineCommensurateOptions::Validate() const {
  if (q < 1 || q > kMaxOnlineCommensurateQ) Fail("q", q, "1..4");
  if (delay_samples < 0 || delay_samples > 1000000) {
    Fail("delay_samples", delay_samples, "0..1000000");
  }
  if (memory_samples < 1 || memory_samples > 1000000) {
    Fail("memory_samples", memory_samples, "1..1000000");
  }
  if (!(input_abs_max > 0.0)) Fail("input_abs_max", input_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  rls.Validate(num_params());
}

OnlineCommensurate::OnlineCommensurate(const OnlineCommensurateOptions& options)
    : options_(options),
      rls_((options.Validate(), options.rls), options.num_params()),
      u_raw_(options.memory_samples),
      y_raw_(options.memory_samples),
      phi_(Eigen::VectorXd::Zero(options.num_params())),
      covariance_(options.num_params(), options.num_params()) {
  const int n = options_.order();
  for (int m = 1; m < n; ++m) {
    orders_.emplace_back(static_cast<double>(m) / options_.q, options_.memory_samples);
  }
  // The regression at k reads [D^{m alpha} u] back to lag n - m + nk (m = 0: n + nk) and
  // [D^{m alpha} y] back to lag n - m.
  for (int m = 0; m < n; ++m) {
    du_.emplace_back(n - m + options_.delay_samples + 1);
    dy_.emplace_back(n - m + 1);
  }
}

double OnlineCommensurate::Difference(int m, double current,
                                      const RingBuffer<double>& history) const {
  if (m == 0) return current;
  return current + orders_[static_cast<std::size_t>(m - 1)].Sum(history);
}

bool OnlineCommensurate::Update(double u, double y) {
  ++k_;
  const int n = options_.order();
  const int nk = options_.delay_samples;
  if (FiniteWithin(u, options_.input_abs_max)) {
    u_good_ = u;
  } else {
    ++bad_inputs_;
  }
  for (int m = 0; m < n; ++m) du_[static_cast<std::size_t>(m)].Push(Difference(m, u_good_, u_raw_));
  u_raw_.Push(u_good_);

  // Values before k = 0 are zero (at rest).  du_ holds k, k-1, ... (u(k) is pushed): lag l is
  // k - l.  dy_ holds k-1, k-2, ... (y(k) is not yet): lag l is k - 1 - l.
  auto u_at = [&](int m, int lag) {
    return lag <= k_ ? du_[static_cast<std::size_t>(m)][lag] : 0.0;
  };
  auto y_at = [&](int m, int lag) {
    return lag < k_ ? dy_[static_cast<std::size_t>(m)][lag] : 0.0;
  };
  for (int i = 1; i < n; ++i) phi_(i - 1) = y_at(n - i, i - 1);  // [D^{(n-i) alpha} y](k-i)
  phi_(n - 1) = y_at(0, n - 1) - u_at(0, n + nk);                // y(k-n) - u(k-n-nk)
  for (int m = 1; m < n; ++m) phi_(n - 1 + m) = -u_at(m, n - m + nk);

  // -[D^2 y](k) = -(y(k) - 2 y(k-1) + y(k-2)): the target, or, for a bad y, the y that the model
  // predicts from it.
  const double y1 = y_at(0, 0);
  const double y2 = y_at(0, 1);
  const bool y_ok = FiniteWithin(y, options_.output_abs_max);
  bool updated = false;
  if (y_ok) {
    updated = rls_.Update(phi_, -(y - 2.0 * y1 + y2)).outcome == RlsOutcome::kUpdated;
  } else {
    ++bad_outputs_;
    y = 2.0 * y1 - y2 - rls_.Predict(phi_);
    if (!std::isfinite(y)) y = y1;
  }
  for (int m = 0; m < n; ++m) dy_[static_cast<std::size_t>(m)].Push(Difference(m, y, y_raw_));
  y_raw_.Push(y);
  return updated;
}

double OnlineCommensurate::c(int m) const {
  const double a_n = rls_.theta()(options_.order() - 1);
  return a_n != 0.0 ? rls_.theta()(options_.order() - 1 + m) / a_n : kNan;
}

void OnlineCommensurate::CStandardDeviations(std::span<double> out) const {
  const int n = options_.order();
  const double a_n = rls_.theta()(n - 1);
  const bool known = a_n != 0.0 && rls_.options().method != RlsMethod::kNlms;
  if (known) rls_.Covariance(covariance_);
  for (int m = 1; m < n; ++m) {
    double& out_m = out[static_cast<std::size_t>(m - 1)];
    if (!known) {
      out_m = kNan;
      continue;
    }
    const int g = n - 1 + m;
    const double c_m = rls_.theta()(g) / a_n;
    // c = g / a_n: dc/dg = 1 / a_n, dc/da_n = -c / a_n.
    const double variance = (covariance_(g, g) - 2.0 * c_m * covariance_(g, n - 1) +
                             c_m * c_m * covariance_(n - 1, n - 1)) /
                            (a_n * a_n);
    out_m = std::sqrt(std::max(0.0, rls_.innovation_variance() * variance));
  }
}

}  // namespace canalid::core
