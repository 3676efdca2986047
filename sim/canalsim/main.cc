// canalsim: the simulated canal.  `canalsim run` is the headless scenario runner that writes CSV,
// `canalsim serve` the canal behind a Modbus PLC, `canalsim plant` a model JSON's plant on a CSV.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "canalid/version.h"
#include "core/system/guarded_main.h"
#include "sim/canal_config.h"
#include "sim/canalsim/plant_command.h"
#include "sim/canalsim/serve_command.h"
#include "sim/config_reader.h"
#include "sim/scenario.h"
#include "sim/scenario_runner.h"

namespace {

constexpr int kExitConfig = 78;     // EX_CONFIG
constexpr int kExitCantCreat = 73;  // EX_CANTCREAT
constexpr int kExitSoftware = 70;   // EX_SOFTWARE

int Run(const std::string& canal_path, const std::string& scenario_path,
        const std::string& out_path, std::optional<std::uint64_t> seed, bool check_only,
        bool quiet) {
  using canalid::sim::ConfigError;
  canalid::sim::Scenario scenario;
  try {
    const canalid::sim::Canal canal = canalid::sim::LoadCanal(canal_path);
    scenario = canalid::sim::LoadScenario(scenario_path, canal);
  } catch (const ConfigError& e) {
    for (const std::string& p : e.problems()) std::cerr << p << '\n';
    return kExitConfig;
  }
  if (check_only) {
    std::cerr << "canalsim: " << canal_path << " and " << scenario_path << " are valid\n";
    return 0;
  }
  std::ofstream out(out_path);
  if (!out) {
    std::cerr << "canalsim: cannot write " << out_path << '\n';
    return kExitCantCreat;
  }
  const auto start = std::chrono::steady_clock::now();
  auto last_report = start;
  auto progress = [&](double t_s) {
    const auto now = std::chrono::steady_clock::now();
    if (quiet || now - last_report < std::chrono::seconds(2)) return;
    last_report = now;
    std::fprintf(stderr, "canalsim: t = %.0f s of %.0f s (%.0f %%)\n", t_s, scenario.duration_s,
                 100.0 * t_s / scenario.duration_s);
  };
  canalid::sim::RunSummary summary;
  try {
    summary = canalid::sim::RunScenario(scenario, seed.value_or(scenario.seed), out, progress);
  } catch (const std::invalid_argument& e) {
    // An infeasible steady state is a configuration problem (targets, structures, flows).
    std::cerr << scenario_path << ": " << e.what() << '\n';
    return kExitConfig;
  } catch (const std::runtime_error& e) {
    std::cerr << "canalsim: " << e.what() << '\n';
    return kExitSoftware;
  }
  out.close();
  if (!out) {
    std::cerr << "canalsim: error while writing " << out_path << '\n';
    return kExitCantCreat;
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!quiet) {
    std::fprintf(stderr,
                 "canalsim: %d rows to %s; simulated %.0f s in %.3f s (%.0fx real time, %ld "
                 "steps)\ncanalsim: mass balance: volume change %.3f m3, inflow %.3f m3, offtakes "
                 "%.3f m3, outflow %.3f m3, error %.3g m3 (%.3g %% of inflow)\n",
                 summary.rows, out_path.c_str(), summary.simulated_s, wall_s,
                 summary.simulated_s / wall_s, summary.steps, summary.mass.volume_change_m3,
                 summary.mass.inflow_volume_m3, summary.mass.offtake_volume_m3,
                 summary.mass.outflow_volume_m3, summary.mass.error_m3,
                 100.0 * summary.mass.relative_error);
  }
  return 0;
}

int Main(int argc, char** argv) {
  CLI::App app{"canalsim: Saint-Venant canal simulator (Preissmann scheme). See docs/canalsim.md."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "canalsim " + std::string(canalid::kVersion));
  CLI::App* run = app.add_subcommand(
      "run", "Run a scenario headless from its steady state and write the outputs as CSV");
  std::string canal_path, scenario_path, out_path;
  std::optional<std::uint64_t> seed;
  bool check_only = false;
  bool quiet = false;
  run->add_option("--canal", canal_path, "Canal TOML file (geometry, structures)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--scenario", scenario_path, "Scenario TOML file (events, outputs, sensors)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--out", out_path, "Output CSV file (time_s first, then the scenario columns)");
  run->add_option("--seed", seed, "Seed of the sensor models (default: the scenario's seed)");
  run->add_flag("--check-config", check_only, "Validate both files and exit (0 or 78)");
  run->add_flag("-q,--quiet", quiet, "No progress or summary on stderr");
  const canalid::sim::ServeCommand serve(app);
  const canalid::sim::PlantCommand plant(app);
  try {
    app.parse(argc, argv);
    if (run->parsed() && !check_only && out_path.empty()) throw CLI::RequiredError("--out");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (serve.selected()) return serve.Run();
  if (plant.selected()) return plant.Run();
  return Run(canal_path, scenario_path, out_path, seed, check_only, quiet);
}

}  // namespace

int main(int argc, char** argv) { return canalid::core::GuardedMain("canalsim", Main, argc, argv); }
