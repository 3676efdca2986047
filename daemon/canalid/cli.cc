#include "daemon/canalid/cli.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>

#include "canalid/version.h"
#include "daemon/canalid/dashboard_command.h"
#include "daemon/canalid/design_command.h"
#include "daemon/canalid/export_command.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/replay_command.h"
#include "daemon/canalid/report_command.h"
#include "daemon/canalid/simulate_command.h"
#include "daemon/canalid/theory_command.h"

namespace canalid::cli {

CLI::Validator FiniteIn(double lo, double hi, bool open_low) {
  std::ostringstream range;
  range << (open_low ? "(" : "[") << lo << ", " << hi << "]";
  const std::string text = range.str();
  return CLI::Validator(
      [lo, hi, open_low, text](std::string& input) -> std::string {
        double value = 0.0;
        std::size_t used = 0;
        try {
          value = std::stod(input, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != input.size()) return "'" + input + "' is not a number";
        const bool above_low = open_low ? value > lo : value >= lo;
        if (!std::isfinite(value) || !above_low || !(value <= hi)) {
          return input + " is out of range (allowed: a finite number in " + text + ")";
        }
        return std::string();
      },
      "FINITE in " + text);
}

CLI::Validator FinitePositive() { return FiniteIn(0.0, std::numeric_limits<double>::max(), true); }

int Run(int argc, char** argv) {
  CLI::App app{"canalid: identification of canal pools from experiment data (offline tool)"};
  app.require_subcommand(1);
  app.footer(
      "Run 'canalid COMMAND --help' for a command's options. Documentation: README.md, docs/.");
  app.set_version_flag("--version", "canalid " + std::string(canalid::kVersion));
  int exit_code = kExitOk;
  IdentifyOptions identify;
  AddIdentifyCommand(app, identify, exit_code);
  DesignOptions design;
  AddDesignCommand(app, design, exit_code);
  SimulateOptions simulate;
  AddSimulateCommand(app, simulate, exit_code);
  ReplayOptions replay;
  AddReplayCommand(app, replay, exit_code);
  ExportOptions export_options;
  AddExportCommand(app, export_options, exit_code);
  ReportOptions report;
  AddReportCommand(app, report, exit_code);
  TheoryOptions theory;
  AddTheoryCommand(app, theory, exit_code);
  DashboardCommandOptions dashboard;
  AddDashboardCommand(app, dashboard, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  } catch (const InputError& e) {
    std::cerr << "canalid: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "canalid: internal error: " << e.what() << "\n";
    return kExitFailure;
  }
  return exit_code;
}

}  // namespace canalid::cli
