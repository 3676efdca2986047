#include "daemon/canalid/export_command.h"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>

#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/log_export.h"
#include "daemon/canalid/terminal_progress.h"
#include "daemon/config/config_loader.h"

namespace canalid::cli {
namespace {

drivers::LogScanResult Scan(const std::string& log, drivers::LogScanOptions options,
                            drivers::LogMessageVisitor& visitor, const std::string& label) {
  TerminalProgress progress(label);
  options.progress = [&](std::uint64_t bytes, std::uint64_t size) {
    progress.Update(size > 0 ? static_cast<double>(bytes) / static_cast<double>(size) : 1.0);
  };
  try {
    return drivers::ScanCanalidLog(log, options, visitor);
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
}

int RunExport(const ExportOptions& options) {
  std::optional<config::DaemonConfig> config;
  drivers::LogScanOptions scan;
  scan.prefix = options.prefix;
  if (!options.config.empty()) {
    try {
      config = daemon::LoadDaemonConfig(options.config);
    } catch (const daemon::ConfigError& e) {
      throw InputError(std::string("--config: ") + e.what());
    }
    if (scan.prefix.empty()) scan.prefix = config->lcm.channel_prefix;
  }
  if (config && !options.reach.empty() && config->FindReach(options.reach) == nullptr)
    throw InputError("--reach " + options.reach + ": not a reach of --config " + options.config);
  ModelParameterCollector parameters;
  Scan(options.log, scan, parameters, "export " + options.log + " (models)");
  LogExporter exporter(options.out, config, options.reach, parameters.names, options.log);
  const drivers::LogScanResult result = Scan(options.log, scan, exporter, "export " + options.log);
  exporter.Finish();
  if (!exporter.has_config()) {
    throw InputError(options.log +
                     ": no canalid configuration message in the log; give the daemon's "
                     "configuration with --config");
  }
  for (const auto& [name, rows] : exporter.rows()) {
    std::cout << (std::filesystem::path(options.out) / name).string() << ": " << rows << " rows\n";
  }
  if (exporter.rows().empty()) std::cerr << "canalid export: no samples of a configured reach\n";
  if (result.end == drivers::LogEnd::kTruncated) {
    std::cerr << "canalid export: warning: " << result.problem
              << " (the events before it are exported)\n";
  }
  if (result.end == drivers::LogEnd::kCorrupt) {
    std::cerr << "canalid export: " << result.problem << " (the events before it are exported)\n";
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

void AddExportCommand(CLI::App& app, ExportOptions& options, int& exit_code) {
  CLI::App* cmd =
      app.add_subcommand("export", "Write the samples and models of an LCM log of canalidd as CSV");
  cmd->footer(
      "Writes DIR/<reach>.csv per reach: time_s (plant seconds: poll sequence x poll_period_s x\n"
      "time_scale), the reach's inflow, outflow, level and actuator channels under their\n"
      "configured names in SI units (NaN where a sample was not valid) and wall_time_s; and\n"
      "DIR/models.csv: every model the daemon published (online and batch) with its parameters,\n"
      "standard deviations and health. The reach files are ready for 'canalid identify'.\n"
      "Examples:\n"
      "  canalid export run.lcmlog --out run-csv\n"
      "  canalid identify --input run-csv/pool2.csv --model id --qin pool2_inflow \\\n"
      "      --qout pool2_outflow --level pool2_level");
  cmd->add_option("LOG", options.log, "LCM log file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", options.out, "Output folder (created)")->required();
  cmd->add_option("--config", options.config,
                  "Daemon configuration to use instead of the one recorded in the log");
  cmd->add_option("--reach", options.reach, "Export this reach only");
  cmd->add_option("--prefix", options.prefix,
                  "LCM channel prefix of the daemon (default: from the log)");
  cmd->callback([&options, &exit_code] { exit_code = RunExport(options); });
}

}  // namespace canalid::cli
