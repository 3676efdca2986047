#include "daemon/canalid/cli.h"

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "canalid/version.h"
#include "daemon/canalid/design_command.h"
#include "daemon/canalid/export_command.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/replay_command.h"
#include "daemon/canalid/report_command.h"
#include "daemon/canalid/simulate_command.h"

namespace canalid::cli {

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
