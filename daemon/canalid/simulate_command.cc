#include "daemon/canalid/simulate_command.h"

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>

#include "core/numerics/metrics.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/csv/csv_table.h"
#include "drivers/json/model_json.h"
#include "drivers/json/model_json_read.h"

namespace canalid::cli {
namespace {

nlohmann::json ReadModelFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the model file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path + ": not JSON: " + e.what());
  }
}

int RunSimulate(const SimulateOptions& options) {
  const nlohmann::json model = ReadModelFile(options.model_json);
  const drivers::CsvTable table = ReadTable(options.input);
  const SimulatedOutput sim = SimulateModel(model, options.model_json, table, options);
  const Eigen::Index rows = sim.y.size();
  const Eigen::VectorXd time = table.time_s().tail(rows);
  try {
    drivers::WriteCsv(options.out, {"time_s", "y"}, {time, sim.y});
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
  nlohmann::json report = {{"model", model.at("model")},
                           {"out", options.out},
                           {"rows", rows},
                           {"first_row", sim.first_row},
                           {"warnings", sim.warnings}};
  std::string output = options.y;
  if (output.empty() && model.contains("output") && model.at("output").is_string()) {
    output = model.at("output").get<std::string>();
  }
  if (!output.empty() && table.HasColumn(output)) {
    const Eigen::VectorXd measured = RequireColumn(table, output).tail(rows);
    report["metrics"] =
        drivers::ToJson(core::ComputeMetrics(measured, sim.y, table.sample_time_s()));
  }
  std::cout << report.dump() << std::endl;
  return 0;
}

}  // namespace

void AddSimulateCommand(CLI::App& app, SimulateOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a model JSON on a CSV input record");
  cmd->footer(
      "Examples:\n"
      "  canalid identify --model frac-foptd --input step.csv --out m.json\n"
      "  canalid simulate --model-json m.json --input other_step.csv --out sim.csv\n"
      "  canalid simulate --model-json pool.json --input F.csv --u q_in,q_out --out sim.csv\n"
      "Input columns: the model's \"inputs\" (as identified; --u overrides): id q_in,q_out;\n"
      "arx its inputs (and its output, for the initial values, when present); foptd, soptd,\n"
      "frac-foptd, frac-ss u; lpv u and its schedule column (arx locals).\n"
      "Process and fractional models start at steady state at the record's first input value.\n"
      "Optional keys default as in docs/model-json.md: offsets 0, discrete models at the record's\n"
      "sample time, frac-foptd's Oustaloup band as identify would choose it for this record.\n"
      "Output: OUT.csv with time_s and y; on stdout a JSON line with the rows written and, when\n"
      "the measured output column is in the input, the metrics. Exit 2 on bad input.");
  cmd->add_option("--model-json", options.model_json,
                  "Model JSON written by canalid identify, or by hand with the required keys of "
                  "docs/model-json.md")
      ->required();
  cmd->add_option("--input", options.input, "CSV file: header row, time_s first, uniform sampling")
      ->required();
  cmd->add_option("--out", options.out, "CSV file to write (time_s, y)")->required();
  cmd->add_option("--u", options.u, "Input column(s), comma-separated (default: the model's)");
  cmd->add_option("--y", options.y, "Measured output column for metrics (default: the model's)");
  cmd->add_option("--schedule", options.schedule, "lpv: scheduling column (default: the model's)");
  cmd->callback([&options, &exit_code] { exit_code = RunSimulate(options); });
}

}  // namespace canalid::cli
