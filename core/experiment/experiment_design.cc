#include "core/experiment/experiment_design.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/signal/prbs.h"

namespace canalid::core {
namespace {

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, a, b, c, d);
  return buffer;
}

void RequireInRange(const char* name, double value, double low, double high) {
  if (!(value >= low && value <= high)) {
    throw std::invalid_argument(std::string("ExperimentDesignRequest.") + name + " = " +
                                std::to_string(value) + " is outside the allowed range [" +
                                std::to_string(low) + ", " + std::to_string(high) + "]");
  }
}

void RequirePositive(const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("ExperimentDesignRequest.") + name + " = " +
                                std::to_string(value) + " must be finite and > 0");
  }
}

}  // namespace

void ExperimentDesignRequest::Validate() const {
  RequirePositive("nominal_flow_m3s", nominal_flow_m3s);
  RequirePositive("expected_delay_s", expected_delay_s);
  RequirePositive("sample_time_s", sample_time_s);
  RequireInRange("amplitude_percent", amplitude_percent, 5.0, 10.0);
  RequireInRange("duration_factor", duration_factor, 5.0, 20.0);
  RequireInRange("max_order", max_order, kMinLfsrOrder, kMaxLfsrOrder);
}

ExperimentDesign DesignPrbsExperiment(const ExperimentDesignRequest& request) {
  request.Validate();
  ExperimentDesign design;
  const double ts = request.sample_time_s;
  const double delay = request.expected_delay_s;

  design.amplitude_m3s = request.amplitude_percent / 100.0 * request.nominal_flow_m3s;
  design.explanation.push_back(
      Format("amplitude %.6g m3/s = %.3g %% of the nominal %.6g m3/s (allowed 5-10 %%)",
             design.amplitude_m3s, request.amplitude_percent, request.nominal_flow_m3s));

  const double half_delay_samples = delay / 2.0 / ts;
  // Far above any sensible experiment, but keeps the integer conversion defined.
  if (half_delay_samples > 1e9) {
    throw std::invalid_argument("ExperimentDesignRequest: expected_delay_s / sample_time_s = " +
                                std::to_string(2.0 * half_delay_samples) +
                                " is too large (at most 2e9 samples)");
  }
  const long rounded = std::lround(half_delay_samples);
  design.clock_period_samples = static_cast<int>(rounded < 1 ? 1 : rounded);
  design.clock_period_s = design.clock_period_samples * ts;
  if (rounded < 1) {
    design.explanation.push_back(
        Format("clock period %.6g s = 1 sample: half the %.6g s delay (%.6g s) is shorter than "
               "half a sample of %.6g s, and the PRBS cannot switch faster than the sampling",
               design.clock_period_s, delay, delay / 2.0, ts));
  } else {
    design.explanation.push_back(
        Format("clock period %.6g s = half the %.6g s delay, rounded to %.0f samples of %.6g s",
               delay / 2.0, delay, design.clock_period_samples, ts));
  }

  const double required_s = request.duration_factor * delay;
  const double clock_s = design.clock_period_s;
  int order = 0;
  for (int n = kMinLfsrOrder; n <= request.max_order; ++n) {
    if (static_cast<double>((std::int64_t{1} << n) - 1) * clock_s >= required_s) {
      order = n;
      break;
    }
  }
  if (order != 0) {
    design.order = order;
    design.num_periods = 1;
    const double period_s = static_cast<double>((std::int64_t{1} << order) - 1) * clock_s;
    design.explanation.push_back(
        Format("order %.0f: the smallest whose period of %.0f clocks (%.6g s) covers %.6g x the "
               "delay",
               order, static_cast<double>((std::int64_t{1} << order) - 1), period_s,
               request.duration_factor) +
        Format(" = %.6g s", required_s));
  } else {
    design.order = request.max_order;
    const double period_s = static_cast<double>((std::int64_t{1} << design.order) - 1) * clock_s;
    design.num_periods = static_cast<int>(std::ceil(required_s / period_s));
    design.explanation.push_back(
        Format("order %.0f (the largest allowed) has a period of %.6g s, shorter than %.6g x the "
               "delay = %.6g s",
               design.order, period_s, request.duration_factor, required_s) +
        Format(": repeated %.0f times", design.num_periods));
  }
  design.num_samples = static_cast<Eigen::Index>(design.num_periods) *
                       (((Eigen::Index{1} << design.order) - 1) * design.clock_period_samples);
  design.duration_s = static_cast<double>(design.num_samples) * ts;
  design.explanation.push_back(Format("duration %.6g s (%.6g min) = %.0f samples, %.3g x the delay",
                                      design.duration_s, design.duration_s / 60.0,
                                      static_cast<double>(design.num_samples),
                                      design.duration_s / delay));
  return design;
}

}  // namespace canalid::core
