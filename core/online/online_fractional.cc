#include "core/online/online_fractional.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineFractionalOptions", name, value, range);
}

RlsOptions WithBox(RlsOptions o) {
  o.lower = Eigen::Vector2d(0.0, -std::numeric_limits<double>::infinity());
  o.upper = Eigen::Vector2d(1.0 - 1e-9, std::numeric_limits<double>::infinity());
  return o;
}

}  // namespace

void OnlineFractionalOptions::Validate() const {
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    Fail("sample_time_s", sample_time_s, "finite, > 0");
  }
  if (alphas.empty()) Fail("alphas.size()", 0, ">= 1");
  for (double a : alphas) {
    if (!(a > 0.0 && a < 2.0)) Fail("alphas[]", a, "0 < alpha < 2");
  }
  if (memory_samples < 1 || memory_samples > 1000000) {
    Fail("memory_samples", memory_samples, "1..1000000");
  }
  if (delay_samples < 0) Fail("delay_samples", delay_samples, ">= 0");
  if (!(input_abs_max > 0.0)) Fail("input_abs_max", input_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  WithBox(rls).Validate(2);
  selector.Validate();
}

OnlineFractionalBank::OnlineFractionalBank(const OnlineFractionalOptions& options)
    : options_(options),
      selector_((options.Validate(), static_cast<int>(options.alphas.size())), options.selector),
      u_history_(options.delay_samples + 1),
      y_history_(options.memory_samples) {
  const RlsOptions rls = WithBox(options_.rls);
  for (double a : options_.alphas) {
    regressors_.emplace_back(a, options_.memory_samples);
    estimators_.emplace_back(rls);
    if (options_.output_error) simulated_.emplace_back(options_.memory_samples);
  }
  predictions_.assign(options_.alphas.size(), 0.0);
}

bool OnlineFractionalBank::Update(double u, double y) {
  ++k_;
  ++health_.samples;
  if (FiniteWithin(u, options_.input_abs_max)) {
    u_good_ = u;
  } else {
    ++health_.bad_inputs;
  }
  u_history_.Push(u_good_);
  const bool y_ok = FiniteWithin(y, options_.output_abs_max);
  const double u_delayed = k_ >= options_.delay_samples ? u_history_[options_.delay_samples] : 0.0;
  for (int i = 0; i < num_candidates(); ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const RingBuffer<double>& history = options_.output_error ? simulated_[ui] : y_history_;
    const Eigen::Vector2d phi(-regressors_[ui].Sum(history), u_delayed);
    predictions_[ui] = estimators_[ui].Predict(phi);
    if (y_ok) {
      const auto result = estimators_[ui].Update(phi, y);
      selector_.Record(i, result.prediction_error);
    }
    // The parallel model's output with the updated parameters (a posteriori), measured y or not.
    if (options_.output_error) simulated_[ui].Push(estimators_[ui].Predict(phi));
  }
  if (y_ok) {
    selector_.Commit();
    y_history_.Push(y);
  } else {
    ++health_.bad_outputs;
    const int s = selector_.selected();
    y_history_.Push(predictions_[static_cast<std::size_t>(s < 0 ? 0 : s)]);
  }
  health_.switches = selector_.switches();
  return y_ok;
}

FractionalSnapshot OnlineFractionalBank::Snapshot() const {
  const int s = selector_.selected();
  if (s < 0) return FractionalSnapshot{};
  return CandidateSnapshot(s);
}

FractionalSnapshot OnlineFractionalBank::CandidateSnapshot(int index) const {
  FractionalSnapshot s;
  if (index < 0 || index >= num_candidates()) return s;
  const auto ui = static_cast<std::size_t>(index);
  const Rls<2>& rls = estimators_[ui];
  s.valid = rls.health().updates > 0;
  s.sample = k_;
  s.alpha = options_.alphas[ui];
  s.theta1 = rls.theta()(0);
  s.theta2 = rls.theta()(1);
  const double c = s.theta1 / (1.0 - s.theta1);
  s.gain = s.theta2 / (1.0 - s.theta1);
  s.time_constant_s = c * std::pow(options_.sample_time_s, s.alpha);
  s.theta1_std = rls.StandardDeviation(0);
  s.theta2_std = rls.StandardDeviation(1);
  // K = theta2 / (1 - theta1), T = h^alpha theta1 / (1 - theta1): gradients in theta, then
  // var = g' sigma2 P g.
  Eigen::Matrix2d p;
  rls.Covariance(p);
  const double one_minus = 1.0 - s.theta1;
  const Eigen::Vector2d gain_gradient(s.theta2 / (one_minus * one_minus), 1.0 / one_minus);
  const double t_gradient = std::pow(options_.sample_time_s, s.alpha) / (one_minus * one_minus);
  const double sigma2 = rls.innovation_variance();
  s.gain_std = std::sqrt(std::max(0.0, sigma2 * gain_gradient.dot(p * gain_gradient)));
  s.time_constant_std_s = std::sqrt(std::max(0.0, sigma2 * p(0, 0))) * t_gradient;
  // Eigenvalues of the symmetric 2 x 2 P in closed form.
  const double mean = 0.5 * (p(0, 0) + p(1, 1));
  const double radius = std::hypot(0.5 * (p(0, 0) - p(1, 1)), p(0, 1));
  const double lambda_max = mean + radius;
  const double lambda_min = mean - radius;
  s.condition_number =
      lambda_min > 0.0 ? lambda_max / lambda_min : std::numeric_limits<double>::infinity();
  s.information_min = lambda_max > 0.0 ? 1.0 / lambda_max : 0.0;
  s.prediction_error = rls.last_prediction_error();
  s.innovation_std = std::sqrt(rls.innovation_variance());
  s.loss = selector_.loss(index);
  s.health = rls.health();
  return s;
}

}  // namespace canalid::core
