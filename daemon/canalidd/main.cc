// canalidd: the identification daemon beside a PLC.  Wiring only: configuration, drivers, loop.
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "canalid/version.h"
#include "daemon/canalidd/daemon.h"
#include "daemon/canalidd/log.h"
#include "daemon/canalidd/plan_builder.h"
#include "daemon/config/config_loader.h"
#include "drivers/lcm/lcm_bus.h"

namespace {

constexpr int kExitConfig = 78;  // EX_CONFIG
constexpr int kExitSoftware = 70;

canalid::daemon::LogLevel ToLogLevel(canalid::core::LogLevel level) {
  switch (level) {
    case canalid::core::LogLevel::kError:
      return canalid::daemon::LogLevel::kError;
    case canalid::core::LogLevel::kWarn:
      return canalid::daemon::LogLevel::kWarning;
    case canalid::core::LogLevel::kInfo:
      return canalid::daemon::LogLevel::kInfo;
    case canalid::core::LogLevel::kDebug:
      return canalid::daemon::LogLevel::kDebug;
  }
  return canalid::daemon::LogLevel::kInfo;
}

// Loads, validates and plans; prints every problem and returns nothing when the file is bad.
std::optional<canalid::daemon::DaemonPlan> LoadPlan(const std::string& path,
                                                    canalid::core::LogLevel* level) {
  try {
    const canalid::core::DaemonConfig config = canalid::daemon::LoadDaemonConfig(path);
    if (level != nullptr) *level = config.daemon.log_level;
    return canalid::daemon::BuildDaemonPlan(config, path,
                                            canalid::daemon::RenderDaemonConfig(config));
  } catch (const canalid::daemon::ConfigError& e) {
    std::cerr << e.what() << (std::string(e.what()).ends_with('\n') ? "" : "\n");
  } catch (const std::exception& e) {
    std::cerr << path << ": " << e.what() << "\n";
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "canalidd: identification daemon for canal pools, beside a PLC (Modbus) on an LCM bus"};
  std::string config_path;
  bool check_only = false;
  app.add_option("-c,--config", config_path,
                 "Configuration file (TOML, see config/canalidd.example.toml)")
      ->required();
  app.add_flag("--check-config", check_only,
               "Validate the configuration, print every problem, and exit (0 or 78)");
  app.set_version_flag("--version", "canalidd " + std::string(canalid::kVersion));
  app.footer(
      "Signals: SIGTERM/SIGINT stop experiments, restore nominal setpoints and exit 0; SIGHUP "
      "reloads\n"
      "the configuration when it is valid. Exit 78: configuration error. Docs: "
      "docs/configuration.md.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitConfig;
  }

  canalid::core::LogLevel level = canalid::core::LogLevel::kInfo;
  std::optional<canalid::daemon::DaemonPlan> plan = LoadPlan(config_path, &level);
  if (!plan) return kExitConfig;
  if (check_only) {
    std::cout << config_path << ": valid\n";
    return 0;
  }
  canalid::daemon::SetLogLevel(ToLogLevel(level));
  try {
    std::unique_ptr<canalid::drivers::LcmBus> bus;
    std::string bus_url;
    while (true) {
      // A reload keeps the bus unless its URL changed: reopening a file:// log would truncate it.
      if (!bus || plan->lcm_url != bus_url) {
        bus.reset();
        bus = std::make_unique<canalid::drivers::LcmBus>(plan->lcm_url);
        bus_url = plan->lcm_url;
      }
      canalid::daemon::Daemon daemon(std::move(*plan), *bus,
                                     canalid::daemon::Daemon::MakeModbusPort,
                                     [&config_path] { return LoadPlan(config_path, nullptr); });
      if (daemon.Run() != canalid::daemon::DaemonExit::kReload) return 0;
      plan = daemon.TakeReloadedPlan();
      if (!plan) return 0;
    }
  } catch (const std::exception& e) {
    canalid::daemon::LogError(std::string("fatal: ") + e.what());
    return kExitSoftware;
  }
}
