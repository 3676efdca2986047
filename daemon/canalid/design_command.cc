#include "daemon/canalid/design_command.h"

#include <CLI/CLI.hpp>
#include <iostream>
#include <stdexcept>

#include "core/experiment/experiment_design.h"
#include "core/signal/prbs.h"
#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "drivers/csv/csv_table.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

int RunDesign(const DesignOptions& options) {
  core::ExperimentDesignRequest request;
  request.nominal_flow_m3s = options.nominal_flow_m3s;
  request.expected_delay_s = options.delay_s;
  request.sample_time_s = options.sample_time_s;
  request.amplitude_percent = options.amplitude_percent;
  core::ExperimentDesign design;
  try {
    design = core::DesignPrbsExperiment(request);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  nlohmann::json json = drivers::ToJson(design);
  json["nominal_flow_m3s"] = options.nominal_flow_m3s;
  json["sample_time_s"] = options.sample_time_s;
  json["seed"] = options.seed;
  if (!options.csv.empty()) {
    core::PrbsSignalSpec spec;
    spec.nominal = options.nominal_flow_m3s;
    spec.amplitude = design.amplitude_m3s;
    spec.clock_period_samples = design.clock_period_samples;
    spec.order = design.order;
    spec.seed = options.seed;
    const Eigen::VectorXd value = core::GeneratePrbs(spec, design.num_samples);
    const Eigen::VectorXd time =
        Eigen::VectorXd::LinSpaced(design.num_samples, 0.0,
                                   static_cast<double>(design.num_samples - 1)) *
        options.sample_time_s;
    try {
      drivers::WriteCsv(options.csv, {"time_s", "value"}, {time, value});
    } catch (const drivers::CsvError& e) {
      throw InputError(e.what());
    }
    json["csv"] = options.csv;
  }
  std::cout << (options.pretty ? json.dump(2) : json.dump()) << std::endl;
  return 0;
}

}  // namespace

void AddDesignCommand(CLI::App& app, DesignOptions& options, int& exit_code) {
  CLI::App* cmd =
      app.add_subcommand("design", "Design a PRBS identification experiment on a pool's inflow");
  cmd->footer(
      "Rules (docs/references.md): amplitude 5-10 % of the nominal flow; clock period about "
      "half\n"
      "the expected delay, a whole number of samples; the smallest LFSR order whose period lasts "
      "at\n"
      "least 5 delays. The JSON's 'explanation' says how each number was chosen.\n"
      "Example:\n"
      "  canalid design --nominal-flow 10 --delay-s 682 --sample-time-s 60 --csv prbs.csv");
  cmd->add_option("--nominal-flow", options.nominal_flow_m3s, "Nominal inflow, m3/s")
      ->required()
      ->check(FinitePositive());
  cmd->add_option("--delay-s", options.delay_s, "Expected delay of the pool, s")
      ->required()
      ->check(FinitePositive());
  cmd->add_option("--sample-time-s", options.sample_time_s, "Sample time, s")
      ->required()
      ->check(FinitePositive());
  cmd->add_option("--amplitude-percent", options.amplitude_percent,
                  "PRBS amplitude, % of the nominal flow (5-10)")
      ->check(FiniteIn(5.0, 10.0))
      ->capture_default_str();
  cmd->add_option("--csv", options.csv, "Write the PRBS inflow as time_s,value");
  cmd->add_option("--seed", options.seed, "Nonzero LFSR start state")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--pretty", options.pretty, "Indent the JSON");
  cmd->callback([&options, &exit_code] { exit_code = RunDesign(options); });
}

}  // namespace canalid::cli
