#include "core/reach/process_batch.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalid::core {
namespace {

std::string BoundsProblem(double gain, double time_constant_s, double delay_s, double max_delay_s) {
  if (!std::isfinite(gain)) return "gain is not finite";
  if (!(time_constant_s > 0.0 && std::isfinite(time_constant_s))) {
    return "time constant " + std::to_string(time_constant_s) + " s is not > 0";
  }
  if (!(delay_s >= 0.0 && delay_s <= max_delay_s)) {
    return "delay " + std::to_string(delay_s) + " s is outside [0, " + std::to_string(max_delay_s) +
           "] s";
  }
  return {};
}

}  // namespace

std::string_view ProcessBatchKindName(ProcessBatchKind kind) {
  switch (kind) {
    case ProcessBatchKind::kFoptd:
      return "foptd";
    case ProcessBatchKind::kFractionalFoptd:
      return "frac-foptd";
    case ProcessBatchKind::kSoptd:
      return "soptd";
  }
  return "?";
}

ProcessBatchResult FitProcessBatch(ProcessBatchKind kind,
                                   const Eigen::Ref<const Eigen::VectorXd>& u,
                                   const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                                   double max_delay_s) {
  ProcessBatchResult result;
  result.kind = kind;
  try {
    if (kind == ProcessBatchKind::kFoptd) {
      ProcessFitOptions options;
      options.max_delay_s = max_delay_s;
      result.foptd = FitFoptd(u, y, sample_time_s, options);
      const FoptdModel& m = result.foptd->model;
      result.problem = BoundsProblem(m.gain, m.time_constant_s, m.delay_s, max_delay_s);
    } else if (kind == ProcessBatchKind::kSoptd) {
      ProcessFitOptions options;
      options.max_delay_s = max_delay_s;
      result.soptd = FitSoptd(u, y, sample_time_s, options);
      const SoptdModel& m = result.soptd->model;
      // T1 >= T2 (FitSoptd): the smaller one must be > 0.
      result.problem = BoundsProblem(m.gain, std::min(m.time_constants_s[0], m.time_constants_s[1]),
                                     m.delay_s, max_delay_s);
    } else {
      FractionalFoptdFitOptions options;
      options.max_delay_s = max_delay_s;
      result.fractional = FitFractionalFoptd(u, y, sample_time_s, options);
      const FractionalFoptdParams& p = result.fractional->params;
      result.band = FitOustaloupBand(p, sample_time_s, u.size(), options);
      result.problem = BoundsProblem(p.gain, p.time_constant_s, p.delay_s, max_delay_s);
    }
  } catch (const std::invalid_argument& e) {
    result.foptd.reset();
    result.soptd.reset();
    result.fractional.reset();
    result.problem = e.what();
  }
  return result;
}

}  // namespace canalid::core
