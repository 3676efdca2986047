#include "daemon/canalid/report_command.h"

#include "daemon/canalid/report_theory.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string_view>

#include "daemon/canalid/child_process.h"
#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/report_analysis.h"
#include "daemon/canalid/report_html.h"
#include "daemon/canalid/report_input.h"
#include "daemon/canalid/report_plots.h"
#include "daemon/canalid/terminal_progress.h"

namespace canalid::cli {
namespace {

std::string CommandLine(const ReportOptions& options) {
  std::string line = "canalid report --input " + options.input + " --model";
  for (const auto& kind : options.models) line += " " + kind;
  return line + " --out " + options.out;
}

void WriteModelFiles(const std::filesystem::path& dir, const std::vector<ModelAnalysis>& models) {
  for (const auto& m : models) {
    const auto path = dir / "models" / (m.kind + ".json");
    std::ofstream out(path, std::ios::trunc);
    if (!(out << m.model.dump(2) << "\n") || !out.flush()) {
      throw ToolError(path.string() + ": cannot write");
    }
  }
}

// "identifying id (1/3)...": the progress line of model i (0-based) of n.
std::string ProgressStep(std::string_view verb, const std::string& kind, std::size_t i,
                         std::size_t n) {
  return std::string(verb) + " " + kind + " (" + std::to_string(i + 1) + "/" + std::to_string(n) +
         ")...";
}

}  // namespace

int RunReport(const ReportOptions& options, const std::string& command_line) {
  if (options.models.empty()) {
    throw InputError(
        "report: no model kind: give --model KIND... (id, idz, arx, foptd, soptd, "
        "frac-foptd, frac-ss, lpv)");
  }
  for (std::size_t i = 0; i < options.models.size(); ++i) {
    if (std::count(options.models.begin(), options.models.end(), options.models[i]) > 1) {
      throw InputError("--model: '" + options.models[i] + "' is given more than once");
    }
  }
  ReportLogOptions log;
  log.reach = options.reach;
  log.config = options.config;
  log.data_dir = (std::filesystem::path(options.out) / "data").string();
  const ReportInput input = LoadReportInput(options.input, log);
  const drivers::CsvTable& table = input.table;
  const IdentifyOptions identify_options =
      input.reach_channels ? WithReachColumns(options.identify, *input.reach_channels)
                           : options.identify;
  RequireIdzOptionsUsed(identify_options, options.models);
  TerminalProgress progress("canalid report");
  std::vector<ModelAnalysis> models;
  const std::size_t n = options.models.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::string& kind = options.models[i];
    progress.Show(ProgressStep("identifying", kind, i, n));
    IdentifyOptions identify = identify_options;
    identify.model = kind;
    identify.input = options.input;
    try {
      const nlohmann::json model = IdentifyModel(identify, table);
      progress.Show(ProgressStep("simulating", kind, i, n));
      models.push_back(AnalyseModel(kind, model, table));
      AddIdzTheory(models.back(), identify, table);
    } catch (const InputError& e) {
      progress.Done();
      throw InputError("--model " + kind + ": " + e.what());
    }
  }
  const std::filesystem::path dir(options.out);
  try {
    std::filesystem::create_directories(dir / "gnuplot");
    std::filesystem::create_directories(dir / "models");
    WriteModelFiles(dir, models);
    const std::vector<Plot> plots = WritePlotScripts(table, models, dir, input.online);
    RenderPlots(plots, options.gnuplot, dir, [&progress](std::size_t i, std::size_t total) {
      progress.Show("plotting " + std::to_string(i + 1) + "/" + std::to_string(total) + "...");
    });
    WriteReportHtml(dir / "index.html", table, command_line, models, plots);
    progress.Done();
    std::cout << "wrote " << (dir / "index.html").string() << " (" << models.size() << " models, "
              << plots.size() << " plots)" << std::endl;
  } catch (const ToolError& e) {
    progress.Done();
    std::cerr << "canalid: report: " << e.what() << "\n";
    return kExitFailure;
  } catch (const std::filesystem::filesystem_error& e) {
    progress.Done();
    std::cerr << "canalid: report: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

void AddReportCommand(CLI::App& app, ReportOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "report", "Identify models on a record and write an HTML report with gnuplot figures");
  cmd->footer(
      "Examples:\n"
      "  canalid report --input pool2.csv --model id foptd frac-ss --u q_in --y level --out rep\n"
      "  canalid report --input run.lcmlog --reach pool2 --model id arx --out pool2-report\n"
      "  canalid report --input F.csv --model lpv --local arx --schedule upstream \\\n"
      "                 --bands 1.0,1.2,1.4,1.6 --u gate --y level --out lpv-report\n"
      "Writes OUT/index.html (self-contained: relative links, no scripts), OUT/*.png,\n"
      "OUT/data/REACH.csv (a log's reach, exported as 'canalid export' does),\n"
      "OUT/models/KIND.json and OUT/gnuplot/ (data and scripts: cd OUT && gnuplot gnuplot/X.gp).\n"
      "Every kind is identified with the same column and model options, as identify takes them.\n"
      "Exit 2 on bad input, 1 when gnuplot is missing or fails.");
  cmd->add_option("--input", options.input,
                  "CSV file (header row, time_s first, uniform sampling) or an LCM log of canalidd")
      ->required();
  cmd->add_option("--reach", options.reach,
                  "LCM log input: the reach (default: the log's only one); its inflow, outflow, "
                  "level and actuator channels become the default columns");
  cmd->add_option("--config", options.config,
                  "LCM log input: daemon configuration instead of the one recorded in the log");
  cmd->add_option("--model", options.models,
                  "Model kinds to identify and show (several: --model id foptd, or id,foptd)")
      ->delimiter(',')
      ->check(CLI::IsMember(ModelKinds()));
  cmd->add_option("--out", options.out, "Directory for the report (created)")->required();
  cmd->add_option("--gnuplot", options.gnuplot, "gnuplot program (name in PATH, or a path)")
      ->capture_default_str();
  AddIdentifyModelOptions(*cmd, options.identify);
  cmd->callback([&options, &exit_code] { exit_code = RunReport(options, CommandLine(options)); });
}

}  // namespace canalid::cli
