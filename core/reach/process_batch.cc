#include "core/reach/process_batch.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/linear/arx_delay_scan.h"

namespace canalid::core {
namespace {

// Half-width of the alpha bounds that hold alpha at ProcessBatchOptions::fixed_alpha (the fit
// needs alpha_min < alpha_max).
constexpr double kFixedAlphaHalfWidth = 1e-9;

// max_delay_s >= 0 in whole samples (the nearest), else -1.
int MaxDelaySamples(double max_delay_s, double sample_time_s) {
  if (!(max_delay_s >= 0.0)) return -1;
  return static_cast<int>(std::min(std::round(max_delay_s / sample_time_s), 1e9));
}

// max_delay_s < 0: no upper bound (the fit's own default bounded it).
std::string BoundsProblem(double gain, double time_constant_s, double delay_s, double max_delay_s) {
  if (!std::isfinite(gain)) return "gain is not finite";
  if (!(time_constant_s > 0.0 && std::isfinite(time_constant_s))) {
    return "time constant " + std::to_string(time_constant_s) + " s is not > 0";
  }
  if (!(delay_s >= 0.0 && (max_delay_s < 0.0 || delay_s <= max_delay_s))) {
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
    case ProcessBatchKind::kArx:
      return "arx";
    case ProcessBatchKind::kFracSs:
      return "frac-ss";
  }
  return "?";
}

ProcessBatchResult FitProcessBatch(ProcessBatchKind kind,
                                   const Eigen::Ref<const Eigen::VectorXd>& u,
                                   const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                                   const ProcessBatchOptions& batch) {
  const double max_delay_s = batch.max_delay_s;
  ProcessBatchResult result;
  result.kind = kind;
  try {
    if (kind == ProcessBatchKind::kFoptd) {
      ProcessFitOptions options;
      options.max_delay_s = max_delay_s;
      result.foptd = FitFoptd(u, y, sample_time_s, options);
      const FoptdModel& m = result.foptd->model;
      result.problem = BoundsProblem(m.gain, m.time_constant_s, m.delay_s, max_delay_s);
    } else if (kind == ProcessBatchKind::kArx) {
      result.input_offset = u.size() > 0 ? u(0) : 0.0;
      result.output_offset = y.size() > 0 ? y(0) : 0.0;
      const Eigen::VectorXd du = u.array() - result.input_offset;
      const Eigen::VectorXd dy = y.array() - result.output_offset;
      // Delays the record can hold: at most a third of it, as the id fit's default.
      const int asked = MaxDelaySamples(max_delay_s, sample_time_s);
      const int max_nk = asked >= 0 ? std::min(asked, static_cast<int>(u.size() / 3))
                                    : static_cast<int>(u.size() / 3);
      const int min_nk = std::max(batch.min_delay_samples, 1);
      if (max_nk < min_nk) {
        result.problem = "the record (" + std::to_string(u.size()) +
                         " samples) is too short for delays of " + std::to_string(min_nk) +
                         " samples and more";
        return result;
      }
      result.arx = FitArxOverDelays(dy, du, batch.arx_na, batch.arx_nb, min_nk, max_nk);
      if (!result.arx->a.allFinite() || !result.arx->b.front().allFinite()) {
        result.problem = "the ARX coefficients are not finite";
      }
    } else if (kind == ProcessBatchKind::kFracSs) {
      // Delays the record can hold; the fit needs 20 q samples beyond the delay.  Default
      // min(record / 10, 100 samples): each candidate costs a simulation.
      const int asked = MaxDelaySamples(max_delay_s, sample_time_s);
      const int fallback = static_cast<int>(std::min<Eigen::Index>(u.size() / 10, 100));
      const int max_nk = std::min(asked >= 0 ? asked : fallback,
                                  static_cast<int>(u.size()) - 20 * batch.frac_ss_q);
      if (max_nk < 0) {
        result.problem =
            "the record (" + std::to_string(u.size()) +
            " samples) is too short for frac-ss with q = " + std::to_string(batch.frac_ss_q);
        return result;
      }
      CommensurateFitOptions options;
      options.memory_length = batch.frac_ss_memory_samples;
      result.memory_samples = batch.frac_ss_memory_samples;
      result.commensurate =
          FitCommensurateScanDelay(u, y, batch.frac_ss_q, max_nk, sample_time_s, options);
      const CommensurateModel& m = result.commensurate->model;
      if (!m.a.allFinite() || !m.c.allFinite() || m.a(m.order() - 1) == 0.0 ||
          !result.commensurate->simulated.allFinite()) {
        result.problem = "the frac-ss model is not finite or its simulation diverges";
      }
    } else if (kind == ProcessBatchKind::kSoptd) {
      ProcessFitOptions options;
      options.max_delay_s = max_delay_s;
      result.soptd = FitSoptd(u, y, sample_time_s, options);
      const SoptdModel& m = result.soptd->model;
      // Both time constants > 0 (a NaN one fails too).
      result.problem = BoundsProblem(m.gain, m.time_constants_s[0], m.delay_s, max_delay_s);
      if (result.problem.empty()) {
        result.problem = BoundsProblem(m.gain, m.time_constants_s[1], m.delay_s, max_delay_s);
      }
    } else {
      FractionalFoptdFitOptions options;
      options.max_delay_s = max_delay_s;
      if (batch.fixed_alpha > 0.0) {
        options.alpha_min = batch.fixed_alpha - kFixedAlphaHalfWidth;
        options.alpha_max = batch.fixed_alpha + kFixedAlphaHalfWidth;
      }
      result.fractional = FitFractionalFoptd(u, y, sample_time_s, options);
      const FractionalFoptdParams& p = result.fractional->params;
      result.band = FitOustaloupBand(p, sample_time_s, u.size(), options);
      result.problem = BoundsProblem(p.gain, p.time_constant_s, p.delay_s, max_delay_s);
    }
  } catch (const std::invalid_argument& e) {
    result.foptd.reset();
    result.soptd.reset();
    result.arx.reset();
    result.fractional.reset();
    result.commensurate.reset();
    result.problem = e.what();
  }
  return result;
}

}  // namespace canalid::core
