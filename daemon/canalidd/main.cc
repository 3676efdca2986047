// canalidd: the identification daemon beside a PLC.  Wiring only: configuration, drivers, loop.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "canalid/version.h"
#include "core/system/guarded_main.h"
#include "daemon/canalidd/daemon.h"
#include "daemon/canalidd/log.h"
#include "daemon/canalidd/plan_builder.h"
#include "daemon/canalidd/startup_check.h"
#include "daemon/config/config_loader.h"
#include "drivers/lcm/lcm_bus.h"

namespace {

constexpr int kExitConfig = 78;  // EX_CONFIG

// Loads, validates and plans; prints every problem and returns nothing when the file is bad.
std::optional<canalid::daemon::DaemonPlan> LoadPlan(const std::string& path,
                                                    canalid::config::LogLevel* level) {
  try {
    const canalid::config::DaemonConfig config = canalid::daemon::LoadDaemonConfig(path);
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

// The same file named twice (also through another spelling of its path) is not a conflict.
bool SameFile(const std::string& a, const std::string& b) {
  if (a == b) return true;
  std::error_code error;
  const bool same = std::filesystem::equivalent(a, b, error);
  return !error && same;
}

int Main(int argc, char** argv) {
  CLI::App app{
      "canalidd: identification daemon for canal pools, beside a PLC (Modbus) on an LCM bus"};
  std::string config_path;
  std::string check_path;
  app.add_option("-c,--config", config_path,
                 "Configuration file (TOML, see config/canalidd.example.toml); runs the daemon")
      ->type_name("FILE");
  // Zero or one value: `--check-config FILE` (the documented form) or `--config FILE
  // --check-config` (the older one); an argument starting with '-' is never taken as the file.
  CLI::Option* check =
      app.add_option("--check-config", check_path,
                     "Validate FILE (or the --config file when FILE is left out), print every "
                     "problem, and exit 0 (valid) or 78: canalidd --check-config FILE")
          ->type_name("[FILE]")
          ->expected(0, 1);
  app.set_version_flag("--version", "canalidd " + std::string(canalid::kVersion));
  app.footer(
      "Run: canalidd --config FILE.  Validate only: canalidd --check-config FILE.\n"
      "Signals: SIGTERM/SIGINT stop experiments, restore nominal setpoints and exit 0; SIGHUP "
      "reloads\n"
      "the configuration when it is valid. Exit 78: configuration or start-up error (bad key "
      "file,\nunusable state directory, bus or PLC settings that cannot be opened). Docs: "
      "docs/configuration.md.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitConfig;
  }
  const bool check_only = check->count() > 0;
  if (!check_path.empty()) {
    if (!config_path.empty() && !SameFile(config_path, check_path)) {
      std::cerr << "canalidd: --config " << config_path << " and --check-config " << check_path
                << " name different files; validate one: canalidd --check-config FILE\n";
      return kExitConfig;
    }
    config_path = check_path;
  }
  if (config_path.empty()) {
    std::cerr << "canalidd: no configuration file: run with --config FILE, validate with "
                 "--check-config FILE (--help)\n";
    return kExitConfig;
  }

  canalid::config::LogLevel level = canalid::config::LogLevel::kInfo;
  std::optional<canalid::daemon::DaemonPlan> plan = LoadPlan(config_path, &level);
  if (!plan) return kExitConfig;
  if (check_only) {
    // The files the configuration names (key file, state directory), with the code the start uses.
    try {
      for (const std::string& note : canalid::daemon::CheckStartup(*plan, false).notes)
        std::cerr << config_path << ": " << note << "\n";
    } catch (const canalid::daemon::StartupError& e) {
      std::cerr << config_path << ": " << e.what() << "\n";
      return kExitConfig;
    }
    std::cout << config_path << ": valid\n";
    return 0;
  }
  canalid::daemon::SetLogLevel(level);
  try {
    std::unique_ptr<canalid::drivers::LcmBus> bus;
    std::string bus_url;
    while (true) {
      // Every problem before the loop runs is a configuration error (exit 78), also after SIGHUP.
      std::optional<canalid::daemon::Daemon> daemon;
      try {
        canalid::daemon::CheckStartup(*plan, true);
        // A reload keeps the bus unless its URL changed: reopening a file:// log would truncate it.
        if (!bus || plan->lcm_url != bus_url) {
          bus.reset();
          bus = std::make_unique<canalid::drivers::LcmBus>(plan->lcm_url);
          bus_url = plan->lcm_url;
        }
        // SIGHUP: a configuration whose key file or state directory is bad is refused like an
        // invalid one, and the running daemon carries on.
        daemon.emplace(std::move(*plan), *bus, canalid::daemon::Daemon::MakeModbusPort,
                       [&config_path]() -> std::optional<canalid::daemon::DaemonPlan> {
                         std::optional<canalid::daemon::DaemonPlan> next =
                             LoadPlan(config_path, nullptr);
                         if (!next) return std::nullopt;
                         try {
                           canalid::daemon::CheckStartup(*next, true);
                         } catch (const canalid::daemon::StartupError& e) {
                           canalid::daemon::LogError(config_path + ": " + e.what());
                           return std::nullopt;
                         }
                         return next;
                       });
      } catch (const std::exception& e) {
        throw canalid::daemon::StartupError(e.what());
      }
      if (daemon->Run() != canalid::daemon::DaemonExit::kReload) return 0;
      plan = daemon->TakeReloadedPlan();
      if (!plan) return 0;
    }
  } catch (const canalid::daemon::StartupError& e) {
    canalid::daemon::LogError(std::string("cannot start: ") + e.what());
    return kExitConfig;
  } catch (const std::exception& e) {
    canalid::daemon::LogError(std::string("fatal: ") + e.what());
    return canalid::core::kExitInternalError;
  }
}

}  // namespace

int main(int argc, char** argv) { return canalid::core::GuardedMain("canalidd", Main, argc, argv); }
