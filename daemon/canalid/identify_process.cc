// `canalid identify --model foptd|soptd|frac-foptd|frac-ss`: the daemon's end-of-experiment
// process fits (core::FitProcessBatch), with their options from the command line.
#include <string>

#include "core/reach/process_batch.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

core::ProcessBatchKind KindOf(const std::string& model) {
  for (const core::ProcessBatchKind kind : core::kProcessBatchKinds) {
    if (core::ProcessBatchKindName(kind) == model) return kind;
  }
  throw InputError("--model " + model + ": not a process model");
}

// The flags' ProcessBatchOptions: the fits' own defaults where a flag is not given, the whole
// record as frac-ss's GL memory (the daemon bounds it, docs/configuration.md).
core::ProcessBatchOptions OptionsFromFlags(const IdentifyOptions& options,
                                           const drivers::CsvTable& table) {
  if (options.model != "frac-ss" && options.q > 0) {
    throw InputError("--q applies to --model frac-ss, not " + options.model);
  }
  if (options.model != "frac-foptd" && options.alpha > 0.0) {
    throw InputError(
        "--alpha applies to --model frac-foptd" +
        std::string(options.model == "frac-ss" ? "; frac-ss takes --q (alpha = 1/q)" : ""));
  }
  core::ProcessBatchOptions batch;
  if (options.max_delay_s > 0.0) {
    OptionSamples(options.max_delay_s, table, "--max-delay-s", true);  // the range check
    batch.max_delay_s = options.max_delay_s;
  }
  batch.fixed_alpha = options.alpha > 0.0 ? options.alpha : 0.0;
  batch.frac_ss_q = options.q > 0 ? options.q : 2;
  batch.frac_ss_memory_samples = 0;
  return batch;
}

}  // namespace

nlohmann::json IdentifyProcessModel(const IdentifyOptions& options,
                                    const drivers::CsvTable& table) {
  const core::ProcessBatchKind kind = KindOf(options.model);
  const core::ProcessBatchOptions batch = OptionsFromFlags(options, table);
  const auto u = RequireMovingColumn(table, options.u);
  const auto y = RequireColumn(table, options.y);
  const core::ProcessBatchResult result =
      core::FitProcessBatch(kind, u, y, table.sample_time_s(), batch);
  if (!result.fitted()) throw InputError(table.source() + ": " + result.problem);
  nlohmann::json json = *drivers::ProcessBatchJson(result, table.sample_time_s());
  if (kind == core::ProcessBatchKind::kFractionalFoptd) json["alpha_fixed"] = options.alpha > 0.0;
  // A model outside the bounds the daemon keeps (a time constant <= 0, a delay past the range):
  // printed, and said.
  if (!result.ok()) json["warnings"].push_back(result.problem);
  return json;
}

}  // namespace canalid::cli
