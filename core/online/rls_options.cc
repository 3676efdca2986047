#include "core/online/rls_options.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const std::string& name, double value, const std::string& range) {
  ThrowOptionOutOfRange("RlsOptions", name, value, range);
}

}  // namespace

void RlsOptions::Validate(int num_params) const {
  if (num_params < 1) Fail("num_params", num_params, ">= 1");
  if (!(forgetting > 0.0 && forgetting <= 1.0)) Fail("forgetting", forgetting, "0 < lambda <= 1");
  if (!(initial_covariance > 0.0 && std::isfinite(initial_covariance))) {
    Fail("initial_covariance", initial_covariance, "finite, > 0");
  }
  if (!(trace_max > 0.0)) Fail("trace_max", trace_max, "> 0");
  if (method == RlsMethod::kConstantTrace && !std::isfinite(trace_max)) {
    Fail("trace_max", trace_max, "finite for kConstantTrace");
  }
  if (!(trace_min >= 0.0 && trace_min < trace_max))
    Fail("trace_min", trace_min, "0 <= . < trace_max");
  if (!(eigen_min >= 0.0 && std::isfinite(eigen_min))) Fail("eigen_min", eigen_min, "finite, >= 0");
  if (!(prior_covariance > 0.0 && std::isfinite(prior_covariance))) {
    Fail("prior_covariance", prior_covariance, "finite, > 0");
  }
  if (!(process_noise >= 0.0 && std::isfinite(process_noise))) {
    Fail("process_noise", process_noise, "finite, >= 0");
  }
  if (!(nlms_step > 0.0 && nlms_step < 2.0)) Fail("nlms_step", nlms_step, "0 < mu < 2");
  if (!(nlms_epsilon > 0.0)) Fail("nlms_epsilon", nlms_epsilon, "> 0");
  if (!(regressor_norm_min >= 0.0)) Fail("regressor_norm_min", regressor_norm_min, ">= 0");
  if (!(excitation_min >= 0.0)) Fail("excitation_min", excitation_min, ">= 0");
  if (!(dead_zone >= 0.0)) Fail("dead_zone", dead_zone, ">= 0");
  if (!(huber > 0.0)) Fail("huber", huber, "> 0");
  if (!(reject > 0.0)) Fail("reject", reject, "> 0");
  if (!(dead_zone < huber && dead_zone < reject)) Fail("dead_zone", dead_zone, "< huber, < reject");
  if (!(cusum_drift >= 0.0)) Fail("cusum_drift", cusum_drift, ">= 0");
  if (!(cusum_threshold > 0.0)) Fail("cusum_threshold", cusum_threshold, "> 0");
  if (!(noise_forgetting >= 0.0 && noise_forgetting <= 1.0)) {
    Fail("noise_forgetting", noise_forgetting, "0 (= lambda) or 0 < nu <= 1");
  }
  if (warmup_samples < 0) Fail("warmup_samples", warmup_samples, ">= 0");
  if (!(regressor_abs_max > 0.0)) Fail("regressor_abs_max", regressor_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  if (lower.size() != 0 && lower.size() != num_params) {
    Fail("lower.size()", static_cast<double>(lower.size()), "0 or num_params");
  }
  if (upper.size() != 0 && upper.size() != num_params) {
    Fail("upper.size()", static_cast<double>(upper.size()), "0 or num_params");
  }
  if (lower.size() != 0 && upper.size() != 0) {
    for (int i = 0; i < num_params; ++i) {
      if (!(lower(i) <= upper(i))) Fail("lower[" + std::to_string(i) + "]", lower(i), "<= upper");
    }
  }
}

}  // namespace canalid::core
