#include "daemon/canalid/replay_command.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>

#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/replay_session.h"
#include "daemon/canalid/terminal_progress.h"
#include "daemon/config/config_loader.h"
#include "drivers/json/model_json_params.h"

namespace canalid::cli {
namespace {

std::string Describe(const ReplayModel& model) {
  std::ostringstream s;
  const nlohmann::json& j = model.json;
  s << "t=+" << model.log_time_s << " s  " << model.reach << "  "
    << (model.batch ? "batch " : "online ") << model.kind << ":";
  if (model.kind != "id") {
    // The model's numbers (its JSON keys, alphabetical), without the health fields.
    for (const auto& [key, value] : j.items()) {
      if (value.is_number() && key.find("_std") == std::string::npos && key != "flags" &&
          key != "samples_used" && key != "sample_time_s" && key != "trace_p" &&
          key != "condition_number" && key != "prediction_error_rms") {
        s << " " << key << " " << value.get<double>();
      }
    }
    return s.str();
  }
  s << " delay " << j.value("delay_s", NAN) << " s, area " << j.value("area_m2", NAN) << " m2";
  if (model.batch && j.contains("metrics"))
    s << ", fit " << j["metrics"].value("fit_percent", NAN) << " %";
  if (!model.batch) s << " (" << j.value("samples", 0) << " samples)";
  return s.str();
}

// Relative difference of the replayed parameters and the last ones published live.
void CompareWithLive(const ReplaySession& session, const ReplayModel& model) {
  const auto reach = session.live_models().find(model.reach);
  if (reach == session.live_models().end()) return;
  const auto live = reach->second.find(ReplaySession::LiveKey(model.kind, model.estimator));
  if (live == reach->second.end()) return;
  // A parameter is a top-level number of the replayed JSON (every online kind's), else one the
  // daemon flattened out of a batch model's arrays (arx's a1.., soptd's time_constant_1_s..).
  const std::vector<drivers::ModelJsonParam> flattened = drivers::ModelJsonParams(model.json);
  double worst = 0.0;
  for (std::size_t i = 0; i < live->second.param_names.size(); ++i) {
    const std::string& name = live->second.param_names[i];
    double a = 0.0;
    if (model.json.contains(name) && model.json[name].is_number()) {
      a = model.json[name].get<double>();
    } else if (const auto it =
                   std::find_if(flattened.begin(), flattened.end(),
                                [&](const drivers::ModelJsonParam& p) { return p.name == name; });
               it != flattened.end()) {
      a = it->value;
    } else {
      continue;
    }
    const double b = live->second.param_values[i];
    worst = std::max(worst, std::abs(a - b) / std::max(std::abs(b), 1e-300));
  }
  std::cerr << "canalid replay: " << model.reach << ": " << (model.batch ? "batch " : "online ")
            << model.kind << " model vs the last one published live: largest relative difference "
            << worst << "\n";
}

int RunReplay(const ReplayOptions& options) {
  ReplaySessionOptions session_options;
  session_options.log_path = options.log;
  session_options.reach = options.reach;
  session_options.from_s = options.from_s;
  session_options.to_s = options.to_s;
  session_options.snapshot_every = options.snapshot_every;
  drivers::LogScanOptions scan;
  scan.prefix = options.prefix;
  if (!options.config.empty()) {
    try {
      session_options.config = daemon::LoadDaemonConfig(options.config);
    } catch (const daemon::ConfigError& e) {
      throw InputError(std::string("--config: ") + e.what());
    }
    if (scan.prefix.empty()) scan.prefix = session_options.config->lcm.channel_prefix;
  }
  auto print = [&](const ReplayModel& model) {
    if (options.json) {
      nlohmann::json line = model.json;
      line["log_time_s"] = model.log_time_s;
      line["estimator"] = model.batch ? "batch" : "online";
      std::cout << line.dump() << "\n";
    } else {
      std::cout << Describe(model) << "\n";
    }
  };
  ReplaySession session(session_options, print,
                        [](const std::string& w) { std::cerr << "canalid replay: " << w << "\n"; });
  TerminalProgress progress("replay " + options.log);
  scan.progress = [&](std::uint64_t bytes, std::uint64_t size) {
    progress.Update(size > 0 ? static_cast<double>(bytes) / static_cast<double>(size) : 1.0,
                    std::to_string(session.samples_used()) + " samples");
  };
  const auto start = std::chrono::steady_clock::now();
  drivers::LogScanResult result;
  try {
    result = drivers::ScanCanalidLog(options.log, scan, session);
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const InputError*>(&e) != nullptr) throw;
    throw InputError(e.what());
  }
  progress.Done();
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!session.has_config()) {
    throw InputError(options.log + ": no canalid configuration message (" +
                     (scan.prefix.empty() ? std::string("<prefix>") : scan.prefix) +
                     "CONFIG) in the log; give the daemon's configuration with --config");
  }
  std::cerr << "canalid replay: " << session.samples_used() << " samples of " << result.events
            << " events (" << result.bytes << " bytes) in " << elapsed << " s\n";
  if (result.end == drivers::LogEnd::kTruncated)
    std::cerr << "canalid replay: warning: " << result.problem
              << " (the events before it are used)\n";
  const std::vector<ReplayModel> finals = session.FinalModels();
  if (finals.empty()) {
    const std::vector<std::string> modelless = session.ReachesWithoutModels();
    if (!modelless.empty() && modelless.size() == session.reach_count() &&
        session.samples_used() > 0) {
      std::string names;
      for (const std::string& name : modelless) names += (names.empty() ? "" : ", ") + name;
      std::cerr << "canalid replay: no model: reach " << names
                << " is configured with none (online_models and batch_models are empty: it only "
                   "moves its actuator in joint experiments)\n";
    } else {
      std::cerr << "canalid replay: no model: no reach had samples for an estimate\n";
    }
    return kExitFailure;
  }
  for (const ReplayModel& model : finals) CompareWithLive(session, model);
  // The last line: the final model JSON of each reach (the selected one alone with --reach).
  for (const ReplayModel& model : finals) std::cout << model.json.dump() << "\n";
  std::cout.flush();
  if (result.end == drivers::LogEnd::kCorrupt) {
    std::cerr << "canalid replay: " << result.problem << " (the events before it are used)\n";
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

void AddReplayCommand(CLI::App& app, ReplayOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "replay", "Run the daemon's pipeline over an LCM log of canalidd (lcm-logger or file://)");
  cmd->footer(
      "Reads the log in process (every message, in order), takes the configuration the daemon\n"
      "recorded on <prefix>CONFIG unless --config is given, and runs each reach's online\n"
      "estimator, experiment and batch identification exactly as canalidd did. Operator\n"
      "commands, write failures and stops are taken from the recorded experiment messages.\n"
      "Prints model snapshots as they come and, as the last line(s), the final ID model JSON\n"
      "of each reach. A truncated log (a logger still writing) is used up to its last whole\n"
      "event (warning); a corrupt one is used up to the damage, named by byte offset, exit 2.\n"
      "Examples:\n"
      "  canalid replay run.lcmlog\n"
      "  canalid replay run.lcmlog --reach pool2 --json --snapshot-every 100\n"
      "  canalid replay run.lcmlog --config other-settings.toml --from 3600 --to 7200");
  cmd->add_option("LOG", options.log, "LCM log file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--config", options.config,
                  "Daemon configuration to use instead of the one recorded in the log");
  cmd->add_option("--reach", options.reach, "Replay this reach only");
  cmd->add_option("--prefix", options.prefix,
                  "LCM channel prefix of the daemon (default: of the first configuration in the "
                  "log, or of --config)");
  cmd->add_option("--from", options.from_s, "Start, seconds after the log's first sample")
      ->check(FiniteIn(std::numeric_limits<double>::lowest(), std::numeric_limits<double>::max()));
  cmd->add_option("--to", options.to_s, "End, seconds after the log's first sample")
      ->check(FiniteIn(std::numeric_limits<double>::lowest(), std::numeric_limits<double>::max()));
  cmd->add_option("--snapshot-every", options.snapshot_every,
                  "Print the online estimate every N samples (0: only batch models and the end)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--json", options.json, "Snapshots as JSON lines instead of text");
  cmd->callback([&options, &exit_code] { exit_code = RunReplay(options); });
}

}  // namespace canalid::cli
