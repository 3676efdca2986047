#include "daemon/canalid/identify_command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "daemon/canalid/cli.h"
#include "daemon/canalid/closed_loop_option.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {
namespace {

int RunIdentify(const IdentifyOptions& options) {
  if (!options.compare.empty()) return RunCompare(options);
  if (options.model.empty()) throw InputError("identify: give --model KIND or --compare KINDS");
  RequireIdzOptionsUsed(options, {options.model});
  const drivers::CsvTable table = ReadTable(options.input);
  const nlohmann::json model = IdentifyModel(options, table);
  const std::string text = options.pretty ? model.dump(2) : model.dump();
  if (!options.out.empty()) {
    std::ofstream out(options.out, std::ios::trunc);
    if (!(out << text << "\n")) throw InputError(options.out + ": cannot write the model file");
  }
  std::cout << text << std::endl;
  return 0;
}

}  // namespace

const std::vector<std::string>& ModelKinds() {
  static const std::vector<std::string> kKinds = {"id",    "idz",        "arx",     "foptd",
                                                  "soptd", "frac-foptd", "frac-ss", "lpv"};
  return kKinds;
}

nlohmann::json IdentifyModel(const IdentifyOptions& options, const drivers::CsvTable& table) {
  nlohmann::json model;
  if (options.online) {
    model = IdentifyOnline(options, table);
  } else if (options.model == "id") {
    model = IdentifyId(options, table);
  } else if (options.model == "idz") {
    model = IdentifyIdz(options, table);
  } else if (options.model == "arx") {
    model = IdentifyArx(options, table);
  } else if (options.model == "lpv") {
    model = IdentifyLpv(options, table);
  } else if (options.model == "foptd" || options.model == "soptd" ||
             options.model == "frac-foptd" || options.model == "frac-ss") {
    model = IdentifyProcessModel(options, table);
  } else {
    throw InputError("--model: unknown kind '" + options.model +
                     "' (id, idz, arx, foptd, soptd, frac-foptd, frac-ss, lpv)");
  }
  // The columns the model was fitted on, so `canalid simulate` finds them again.
  if (!model.contains("inputs")) {
    const bool pool_model = options.model == "id" || options.model == "idz";
    model["inputs"] = pool_model ? std::vector<std::string>{options.qin, options.qout}
                                 : std::vector<std::string>{options.u};
    model["output"] = pool_model ? options.level : options.y;
  }
  model["input"] = {
      {"file", options.input}, {"rows", table.rows()}, {"sample_time_s", table.sample_time_s()}};
  return model;
}

void RequireIdzOptionsUsed(const IdentifyOptions& options, const std::vector<std::string>& kinds) {
  const bool idz = std::find(kinds.begin(), kinds.end(), "idz") != kinds.end();
  const bool held_p22 = options.online && options.model == "id";
  if (!idz && !held_p22 && options.p22 >= 0.0) {
    throw InputError("--p22 applies to --model idz and to --model id --online");
  }
  if (!idz && !options.canal.empty()) throw InputError("--canal applies to --model idz");
  if (idz && kinds.size() == 1 && options.closed_loop != "auto") {
    throw InputError("--closed-loop applies to --model id (idz's p22 settles the closed loop)");
  }
  if (!idz && options.p22_std >= 0.0) throw InputError("--p22-std applies to --model idz");
}

void AddIdentifyModelOptions(CLI::App& cmd, IdentifyOptions& options) {
  auto* id = cmd.add_option_group("ID and IDZ models (--model id|idz)");
  id->add_option("--qin", options.qin, "Inflow column, m3/s")->capture_default_str();
  id->add_option("--qout", options.qout, "Outflow column, m3/s")->capture_default_str();
  id->add_option("--level", options.level, "Downstream level column, m")->capture_default_str();
  id->add_option("--max-delay-s", options.max_delay_s,
                 "Longest delay tried, s (id, foptd, soptd: a third of the record; frac-foptd: "
                 "half; frac-ss: min(record/10, 100 samples); lpv arx/frac-ss locals: 20 "
                 "samples)")
      ->check(FiniteIn(0.0, 1e9, true));
  AddClosedLoopOption(*id, options.closed_loop);
  id->add_option("--p22", options.p22,
                 "IDZ direct outflow gain p22, s/m2 (canalid theory's p22_low_frequency_s_per_m2): "
                 "idz's prior, or with --online id held (fits level + p22 q_out).  With a "
                 "level-driven gate b cannot be told from p22, so without it the area comes out "
                 "as A (1 + p22 g)")
      ->check(FiniteIn(0.0, 10.0));
  id->add_option("--p22-std", options.p22_std,
                 "idz: standard deviation of the --p22 prior, s/m2 (default 20 % of it)")
      ->check(FiniteIn(0.0, 10.0));
  auto* canal = id->add_option("--canal", options.canal,
                               "idz: canal file (canalsim's TOML) whose --pool's geometry gives "
                               "the p22 prior at the record's mean inflow (canalid theory)")
                    ->check(CLI::ExistingFile);
  auto* pool = id->add_option("--pool", options.pool, "idz: the pool of --canal");
  canal->needs(pool);
  pool->needs(canal);
  id->add_flag("--keep-outliers", options.keep_outliers,
               "Do not replace level spikes before fitting");
  auto* io = cmd.add_option_group(
      "Input/output models (arx, foptd, soptd, frac-foptd, frac-ss, lpv, --compare)");
  io->add_option("--u", options.u, "Input column(s); arx takes a comma-separated list")
      ->capture_default_str();
  io->add_option("--y", options.y, "Output column")->capture_default_str();
  auto* arx = cmd.add_option_group("ARX (--model arx), MATLAB conventions");
  arx->add_option("--na", options.na, "Number of a coefficients")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  arx->add_option("--nb", options.nb, "b coefficients: one value, or one per input (N[,N...])")
      ->capture_default_str();
  arx->add_option("--nk", options.nk, "Delays in samples: one value, or one per input")
      ->capture_default_str();
  arx->add_flag("--detrend", options.detrend, "Remove linear trends from y and every u first");
  auto* frac = cmd.add_option_group("Fractional models (--model frac-foptd|frac-ss)");
  auto* alpha = frac->add_option("--alpha", options.alpha,
                                 "frac-foptd: hold alpha at this value (0 < A < 2), fit the rest")
                    ->check(FiniteIn(1e-6, 2.0 - 1e-6));
  auto* q = frac->add_option("--q", options.q, "frac-ss: commensurate order alpha = 1/q (1, 2, 4)")
                ->check(CLI::IsMember({1, 2, 4}));
  alpha->excludes(q);
  auto* lpv = cmd.add_option_group("LPV (--model lpv)");
  lpv->add_option("--local", options.local,
                  "Local model per band: arx (first order with delay), frac-foptd, frac-ss "
                  "(with --q), integer (the LPV paper's k e^-tau s/(s(S s^2+M s+1)))");
  lpv->add_option("--schedule", options.schedule, "Scheduling column (theta)");
  lpv->add_option("--bands", options.bands, "Band edges b0,b1,...,bn, strictly increasing");
  lpv->add_option("--bands-file", options.bands_file,
                  "File with the band edges (numbers separated by commas, spaces or lines)");
  lpv->add_option("--degree", options.degree, "Polynomial degree of every parameter in theta")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  lpv->add_option("--min-band-samples", options.min_band_samples,
                  "Fewest consecutive samples a band must have")
      ->check(CLI::Range(10, 100000000))
      ->capture_default_str();
}

// The model's flags and columns: with --config the reach's settings and channel names are used
// instead, so each of these is refused beside it.
constexpr std::array kReachSettingFlags = {
    "--qin",     "--qout",     "--level", "--max-delay-s",   "--closed-loop", "--p22",
    "--p22-std", "--canal",    "--pool",  "--keep-outliers", "--u",           "--y",
    "--na",      "--nb",       "--nk",    "--detrend",       "--alpha",       "--q",
    "--local",   "--schedule", "--bands", "--bands-file",    "--degree",      "--min-band-samples"};

void AddIdentifyCommand(CLI::App& app, IdentifyOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand("identify", "Identify a model from a CSV experiment record");
  cmd->footer(
      "Examples:\n"
      "  canalid identify --model id --input pool2.csv --max-delay-s 3600\n"
      "  canalid identify --model idz --input gate.csv --canal config/sim/asce-canal2.toml --pool "
      "2\n"
      "  canalid identify --model foptd --input step.csv --u gate --y level --pretty\n"
      "  canalid identify --model arx --input F.csv --u u1,u2 --y y --na 2 --nb 2,3 --nk 1,2\n"
      "  canalid identify --model frac-foptd --input step.csv --u gate --y level\n"
      "  canalid identify --model frac-foptd --input step.csv --alpha 0.8\n"
      "  canalid identify --model frac-ss --input step.csv --q 2 --max-delay-s 6\n"
      "  canalid identify --model lpv --local arx --schedule level_up --bands 1.0,1.2,1.4,1.6 \\\n"
      "                   --input F.csv --u q_in --y level\n"
      "  canalid identify --model arx --input F.csv --u u --y y --online --forgetting 0.999\n"
      "  canalid identify --model id --input pool2.csv --online --trace trace.csv\n"
      "  canalid identify --model id --input gate.csv --online --closed-loop iv --p22 0.0216\n"
      "  canalid identify --model frac-foptd --input flume.csv --u gate --y level --online --nk "
      "27\n"
      "  canalid identify --model frac-foptd --input export/pool2.csv --online \\\n"
      "                   --config canalidd.toml --reach pool2\n"
      "  canalid identify --compare foptd,soptd,frac-foptd --input 'steps/*.csv' [--json]\n"
      "Output: one JSON object on stdout (keys in docs/model-json.md); --compare prints a table.\n"
      "Exit 2 on bad input.");
  auto* model =
      cmd->add_option("--model", options.model, "Model kind")->check(CLI::IsMember(ModelKinds()));
  auto* compare = cmd->add_option("--compare", options.compare,
                                  "Comma-separated kinds (foptd, soptd, frac-foptd, frac-ss) to "
                                  "fit to every file of --input (a glob), then print the table");
  model->excludes(compare);
  cmd->add_option("--input", options.input,
                  "CSV file: header row, time_s first, uniform sampling (--compare: a glob, quote "
                  "it)")
      ->required();
  cmd->add_option("--out", options.out, "Also write the model JSON to this file");
  cmd->add_flag("--pretty", options.pretty, "Indent the JSON");
  AddIdentifyModelOptions(*cmd, options);
  auto* online = cmd->add_option_group(
      "Online estimation (--model id|arx|frac-foptd|lpv|idz|frac-ss --online)");
  auto* online_flag =
      online->add_flag("--online", options.online,
                       "Run the recursive estimator sample by sample; print its final snapshot");
  auto* forgetting =
      online->add_option("--forgetting", options.forgetting, "Forgetting factor lambda, 0 < L <= 1")
          ->capture_default_str();
  auto* initial_covariance =
      online->add_option("--initial-covariance", options.initial_covariance,
                         "P0 = p0 I, 0 < p0 <= 1e20 (default as the daemon's initial_covariance: "
                         "1e10)");
  auto* method = online
                     ->add_option("--method", options.method,
                                  "Update law: ud_directional, ud_exponential, exponential, "
                                  "directional, constant_trace, stabilised, kalman, nlms")
                     ->capture_default_str();
  auto* trace =
      online->add_option("--trace", options.trace,
                         "Write the parameter and health trajectory to this CSV (time_s first)");
  auto* config = online->add_option(
      "--config", options.config,
      "--online: a canalidd configuration; the estimator takes the settings of --reach (as the "
      "daemon runs it) and its channel names as columns (the model's flags and columns are "
      "refused beside it)");
  auto* reach = online->add_option("--reach", options.reach, "--config: the reach");
  config->needs(reach);
  reach->needs(config);
  // The reach's settings and channel names come from the configuration; a flag beside it would
  // do nothing.
  for (CLI::Option* setting : {forgetting, initial_covariance, method}) config->excludes(setting);
  for (const char* name : kReachSettingFlags) config->excludes(cmd->get_option(name));
  // The estimator's settings mean nothing to a batch fit.
  for (CLI::Option* setting : {forgetting, initial_covariance, method, trace, config}) {
    setting->needs(online_flag);
  }
  cmd->add_flag("--json", options.json, "--compare: print JSON (summary and per-file) instead");
  cmd->callback([&options, &exit_code] { exit_code = RunIdentify(options); });
}

}  // namespace canalid::cli
