#include "daemon/canalid/theory_command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <complex>
#include <iostream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/hydraulics/idz_model.h"
#include "core/hydraulics/idz_theory.h"
#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/pool_theory.h"
#include "drivers/csv/csv_table.h"
#include "drivers/json/model_json.h"
#include "sim/canal_config.h"
#include "sim/hydraulics.h"

namespace canalid::cli {
namespace {

// One pool's theory and the conditions it was computed for.
struct PoolResult {
  std::string name;
  double flow_m3s = 0.0;
  double downstream_depth_m = 0.0;
  core::IdzTheory theory;
};

nlohmann::json ToJson(const PoolResult& p) {
  const core::IdzModel& m = p.theory.model;
  nlohmann::json json;
  json["pool"] = p.name;
  json["model"] = "idz";
  json["source"] = "geometry (Litrico & Fromion 2004)";
  json["flow_m3s"] = p.flow_m3s;
  json["delay_s"] = m.delay_s;
  json["area_m2"] = m.area_m2;
  json["p21_s_per_m2"] = m.p21_s_per_m2;
  json["p22_s_per_m2"] = m.p22_s_per_m2;
  json["p22_low_frequency_s_per_m2"] = p.theory.outflow_gain_low_frequency_s_per_m2;
  json["delay_low_frequency_s"] = p.theory.delay_low_frequency_s;
  json["upstream_delay_s"] = m.upstream_delay_s;
  json["upstream_area_m2"] = m.upstream_area_m2;
  json["p11_s_per_m2"] = m.p11_s_per_m2;
  json["p12_s_per_m2"] = m.p12_s_per_m2;
  json["regime"] = p.theory.uniform_length_m > 0.0 ? "uniform then backwater" : "backwater";
  json["normal_depth_m"] = p.theory.normal_depth_m;
  json["uniform_length_m"] = p.theory.uniform_length_m;
  json["upstream_depth_m"] = p.theory.upstream_depth_m;
  json["downstream_depth_m"] = p.downstream_depth_m;
  return json;
}

void WriteBode(const TheoryOptions& options, const std::vector<PoolResult>& pools) {
  double smallest_delay = std::numeric_limits<double>::infinity();
  for (const PoolResult& p : pools)
    smallest_delay = std::min(smallest_delay, p.theory.model.delay_s);
  const double low = options.bode_min_rad_s > 0.0 ? options.bode_min_rad_s : 0.01 / smallest_delay;
  const double high =
      options.bode_max_rad_s > 0.0 ? options.bode_max_rad_s : 100.0 / smallest_delay;
  if (!(high > low)) {
    std::ostringstream os;
    os << "--bode-max-rad-s " << high << " must be above --bode-min-rad-s " << low;
    throw InputError(os.str());
  }
  const auto n = static_cast<Eigen::Index>(options.bode_points);
  const Eigen::Index rows = n * static_cast<Eigen::Index>(pools.size());
  Eigen::VectorXd pool_index(rows), omega(rows), g21(rows), ph21(rows), g22(rows), ph22(rows);
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < pools.size(); ++k) {
    for (Eigen::Index i = 0; i < n; ++i, ++row) {
      const double w =
          low * std::pow(high / low, static_cast<double>(i) /
                                         static_cast<double>(std::max<Eigen::Index>(n - 1, 1)));
      const std::complex<double> h21 = core::IdzDownstreamFromInflow(pools[k].theory.model, w);
      const std::complex<double> h22 = core::IdzDownstreamFromOutflow(pools[k].theory.model, w);
      pool_index(row) = static_cast<double>(k);
      omega(row) = w;
      g21(row) = std::abs(h21);
      ph21(row) = core::IdzDownstreamFromInflowPhase(pools[k].theory.model, w) * kDegrees;
      g22(row) = std::abs(h22);
      ph22(row) = std::arg(h22) * kDegrees;
    }
  }
  try {
    drivers::WriteCsv(options.bode,
                      {"pool_index", "omega_rad_s", "p21_gain_s_per_m2", "p21_phase_deg",
                       "p22_gain_s_per_m2", "p22_phase_deg"},
                      {pool_index, omega, g21, ph21, g22, ph22});
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
}

int RunTheory(const TheoryOptions& options) {
  sim::Canal canal;
  std::vector<double> steady_flows;
  try {
    canal = sim::LoadCanal(options.canal);
    // The steady flows only when they are used: --flow replaces them.
    if (!(options.flow_m3s > 0.0)) steady_flows = sim::SteadyPoolFlows(canal);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  std::vector<PoolResult> pools;
  for (std::size_t i = 0; i < canal.pools.size(); ++i) {
    const sim::Pool& pool = canal.pools[i];
    if (!options.all && pool.name != options.pool) continue;
    PoolResult p;
    p.name = pool.name;
    p.flow_m3s = options.flow_m3s > 0.0 ? options.flow_m3s : steady_flows[i];
    p.downstream_depth_m = pool.target_depth_m;
    p.theory = TheoryOf(options.canal, pool, p.flow_m3s);
    pools.push_back(p);
  }
  if (pools.empty()) throw InputError(NotAPoolMessage(canal, options.canal, options.pool));
  nlohmann::json json;
  if (options.all) {
    json["canal"] = canal.name;
    json["pools"] = nlohmann::json::array();
    for (const PoolResult& p : pools) json["pools"].push_back(ToJson(p));
  } else {
    json = ToJson(pools.front());
    json["canal"] = canal.name;
  }
  if (!options.bode.empty()) {
    WriteBode(options, pools);
    json["bode"] = options.bode;
  }
  std::cout << (options.pretty ? json.dump(2) : json.dump()) << std::endl;
  return 0;
}

}  // namespace

void AddTheoryCommand(CLI::App& app, TheoryOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "theory", "The IDZ model a pool's geometry gives (Litrico & Fromion 2004), as JSON");
  cmd->footer(
      "The canal file is canalsim's (docs/canalsim.md): each pool's length, trapezoidal section,\n"
      "bed slope, Manning n and downstream depth; the flow defaults to the pool's flow at the\n"
      "canal's steady state. Method and accuracy: docs/closed-loop.md.\n"
      "Examples:\n"
      "  canalid theory --canal config/sim/asce-canal2.toml --pool 2\n"
      "  canalid theory --canal config/sim/asce-canal2.toml --pool 2 --flow 2.5\n"
      "  canalid theory --canal config/sim/asce-canal1.toml --all --bode bode.csv");
  cmd->add_option("--canal", options.canal, "Canal description (TOML)")
      ->required()
      ->check(CLI::ExistingFile);
  CLI::Option* pool = cmd->add_option("--pool", options.pool, "Name of the pool");
  CLI::Option* all = cmd->add_flag("--all", options.all, "Every pool at the canal's steady flows");
  pool->excludes(all);
  cmd->add_option("--flow", options.flow_m3s, "Flow through the pool, m3/s")
      ->check(FinitePositive())
      ->needs(pool);
  CLI::Option* bode = cmd->add_option(
      "--bode", options.bode, "Write the frequency responses p21(jw), p22(jw) of each pool as CSV");
  cmd->add_option("--bode-min-rad-s", options.bode_min_rad_s,
                  "Lowest frequency of --bode, rad/s (default 0.01 / the smallest delay)")
      ->check(FinitePositive())
      ->needs(bode);
  cmd->add_option("--bode-max-rad-s", options.bode_max_rad_s,
                  "Highest frequency of --bode, rad/s (default 100 / the smallest delay)")
      ->check(FinitePositive())
      ->needs(bode);
  cmd->add_option("--bode-points", options.bode_points, "Frequencies per pool in --bode")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str()
      ->needs(bode);
  cmd->add_flag("--pretty", options.pretty, "Indent the JSON");
  cmd->callback([&options, &exit_code, pool, all] {
    if (pool->count() == 0 && all->count() == 0) {
      throw InputError("theory: give --pool NAME or --all");
    }
    exit_code = RunTheory(options);
  });
}

}  // namespace canalid::cli
