#include "daemon/canalid/identify_command.h"

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>

#include "daemon/canalid/input_error.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {
namespace {

int RunIdentify(const IdentifyOptions& options) {
  drivers::CsvTable table;
  try {
    table = drivers::CsvTable::Read(options.input);
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
  nlohmann::json model;
  if (options.model == "id") {
    model = IdentifyId(options, table);
  } else if (options.model == "arx") {
    model = IdentifyArx(options, table);
  } else {
    model = IdentifyProcessModel(options, table);
  }
  model["input"] = {
      {"file", options.input}, {"rows", table.rows()}, {"sample_time_s", table.sample_time_s()}};
  const std::string text = options.pretty ? model.dump(2) : model.dump();
  if (!options.out.empty()) {
    std::ofstream out(options.out, std::ios::trunc);
    if (!(out << text << "\n")) throw InputError(options.out + ": cannot write the model file");
  }
  std::cout << text << std::endl;
  return 0;
}

}  // namespace

void AddIdentifyCommand(CLI::App& app, IdentifyOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("identify", "Identify a model from a CSV experiment record");
  cmd->footer(
      "Examples:\n"
      "  canalid identify --model id --input pool2.csv --max-delay-s 3600\n"
      "  canalid identify --model foptd --input step.csv --u gate --y level --pretty\n"
      "  canalid identify --model arx --input F.csv --u u1,u2 --y y --na 2 --nb 2,3 --nk 1,2\n"
      "Output: one JSON object on stdout (keys in docs/model-json.md). Exit 2 on bad input.");
  cmd->add_option("--model", options.model, "Model kind")
      ->required()
      ->check(CLI::IsMember({"id", "arx", "foptd", "soptd"}));
  cmd->add_option("--input", options.input, "CSV file: header row, time_s first, uniform sampling")
      ->required();
  cmd->add_option("--out", options.out, "Also write the model JSON to this file");
  cmd->add_flag("--pretty", options.pretty, "Indent the JSON");
  auto* id = cmd->add_option_group("ID model (--model id)");
  id->add_option("--qin", options.qin, "Inflow column, m3/s")->capture_default_str();
  id->add_option("--qout", options.qout, "Outflow column, m3/s")->capture_default_str();
  id->add_option("--level", options.level, "Downstream level column, m")->capture_default_str();
  id->add_option("--max-delay-s", options.max_delay_s,
                 "Longest delay tried, s (default: a third of the record)")
      ->check(CLI::PositiveNumber);
  id->add_option("--closed-loop", options.closed_loop,
                 "auto: decide from the data; on: three-step method; off: plain fit")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  id->add_flag("--keep-outliers", options.keep_outliers,
               "Do not replace level spikes before fitting");
  auto* io = cmd->add_option_group("Input/output models (--model arx|foptd|soptd)");
  io->add_option("--u", options.u, "Input column(s); arx takes a comma-separated list")
      ->capture_default_str();
  io->add_option("--y", options.y, "Output column")->capture_default_str();
  auto* arx = cmd->add_option_group("ARX (--model arx), MATLAB conventions");
  arx->add_option("--na", options.na, "Number of a coefficients")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  arx->add_option("--nb", options.nb, "b coefficients: one value, or one per input (N[,N...])")
      ->capture_default_str();
  arx->add_option("--nk", options.nk, "Delays in samples: one value, or one per input")
      ->capture_default_str();
  arx->add_flag("--detrend", options.detrend, "Remove linear trends from y and every u first");
  cmd->callback([&options, &exit_code] { exit_code = RunIdentify(options); });
}

}  // namespace canalid::cli
