#pragma once
// One identification experiment of canalidd run to its end, for the live daemon suites: a shipped
// configuration rewritten for the test (PLC port, state directory, the experiment to start at
// once), the daemon run with its LCM log in a file, and what it published: the batch models it
// logged, its last online snapshot of each kind before them, the experiments its state messages
// named, and the batch models `canalid replay` finds again in the log.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <canalid/experiment_state_t.hpp>
#include <canalid/model_snapshot_t.hpp>

#include "tests/support/child_process.h"
#include "tests/support/json_after.h"
#include "tests/support/run_program.h"

namespace canalid::testing {

/// `source` (a canalidd TOML) with every whole line `key = ...` whose key is in `keys` replaced by
/// `key = value`, and `start = "manual"` of the [[experiment]] named `on_start` (unless empty) made
/// "on_start". Fails the test when a key or the experiment is not found.
inline std::string RewriteDaemonConfig(const std::filesystem::path& source,
                                       const std::map<std::string, std::string>& keys,
                                       const std::string& on_start) {
  std::ifstream in(source);
  std::ostringstream out;
  std::string line;
  std::string experiment;
  std::set<std::string> found;
  bool started = false;
  while (std::getline(in, line)) {
    const std::size_t eq = line.find(" = ");
    const std::string key = eq == std::string::npos ? "" : line.substr(0, eq);
    if (const auto it = keys.find(key); it != keys.end()) {
      line = key + " = " + it->second;
      found.insert(key);
    } else if (key == "name") {
      experiment = line.substr(eq + 3);
    } else if (!on_start.empty() && line == "start = \"manual\"" &&
               experiment == "\"" + on_start + "\"") {
      line = "start = \"on_start\"";
      started = true;
    }
    out << line << "\n";
  }
  EXPECT_EQ(found.size(), keys.size()) << source << ": a key to replace is missing";
  EXPECT_TRUE(started || on_start.empty()) << source << ": no manual experiment " << on_start;
  return out.str();
}

/// A parameter of a snapshot by name (NaN when it has none).
inline double SnapshotParam(const canalid::model_snapshot_t& m, const std::string& name) {
  for (std::size_t i = 0; i < m.param_names.size(); ++i) {
    if (m.param_names[i] == name) return m.param_values[i];
  }
  return std::nan("");
}

// clang-tidy 14 finds a throw under nlohmann::json's noexcept move constructor (in a debug
// assertion of its invariant) and reports this struct's implicit one (as for PersistedModel).
// NOLINTNEXTLINE(bugprone-exception-escape)
struct DaemonExperimentRun {
  std::string output;                           ///< the daemon's log
  std::map<std::string, nlohmann::json> batch;  ///< kind -> the batch model it logged
  /// kind -> parameter -> value of the last online snapshot before the first batch model.
  std::map<std::string, std::map<std::string, double>> online;
  std::set<std::string> experiments;               ///< the names the state messages carry
  std::map<std::string, nlohmann::json> replayed;  ///< kind -> `canalid replay`'s batch model
  std::string replay_err;                          ///< `canalid replay`'s stderr
};

/// Every model_snapshot_t on `channel` of the LCM log `path`, in order (none when it cannot be
/// read).
inline std::vector<canalid::model_snapshot_t> ModelMessagesIn(const std::filesystem::path& path,
                                                              const std::string& channel) {
  std::vector<canalid::model_snapshot_t> messages;
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) return messages;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != channel) continue;
    canalid::model_snapshot_t m;
    if (m.decode(e->data, 0, e->datalen) == e->datalen) messages.push_back(m);
  }
  return messages;
}

/// Runs canalidd on `config` (written to dir/canalidd.toml; LCM to dir/run.lcmlog) until it logs
/// "reach REACH: experiment done" (at most `timeout_ms`), stops it with SIGTERM, reads what it
/// published on `prefix`MODEL_`reach` and `prefix`EXPERIMENT_`reach`, and replays the log.
inline DaemonExperimentRun RunDaemonExperiment(const std::filesystem::path& dir,
                                               const std::string& config, const std::string& reach,
                                               const std::string& prefix, int timeout_ms) {
  DaemonExperimentRun run;
  WriteFile(dir / "canalidd.toml", config);
  {
    ChildProcess daemon({DaemonProgram(), "--config", (dir / "canalidd.toml").string()},
                        {"LCM_DEFAULT_URL=file://" + (dir / "run.lcmlog").string() + "?mode=w"},
                        dir / "canalidd.log");
    EXPECT_FALSE(daemon.WaitForLine("reach " + reach + ": experiment done", timeout_ms).empty())
        << daemon.output();
    EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();
    run.output = daemon.output();
  }
  std::istringstream lines(run.output);
  std::string line;
  const std::string marker = "reach " + reach + ": identified ";
  while (std::getline(lines, line)) {
    const std::size_t at = line.find(marker);
    if (at == std::string::npos) continue;
    const std::string rest = line.substr(at + marker.size());
    // "identified {json}" is the id model; "identified KIND {json}" the others.
    const std::string kind = rest.rfind('{', 0) == 0 ? "id" : rest.substr(0, rest.find(' '));
    run.batch[kind] = JsonAfter(rest, kind == "id" ? "" : kind + " ");
  }
  const std::string experiment_channel = prefix + "EXPERIMENT_" + reach;
  const std::string model_channel = prefix + "MODEL_" + reach;
  lcm::LogFile log((dir / "run.lcmlog").string(), "r");
  bool batch_seen = false;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == experiment_channel) {
      canalid::experiment_state_t state;
      if (state.decode(e->data, 0, e->datalen) == e->datalen)
        run.experiments.insert(state.experiment);
    } else if (e->channel == model_channel && !batch_seen) {
      canalid::model_snapshot_t m;
      if (m.decode(e->data, 0, e->datalen) != e->datalen) continue;
      if (m.estimator == "batch") {
        batch_seen = true;
        continue;
      }
      auto& params = run.online[m.model_kind];
      for (std::size_t i = 0; i < m.param_names.size(); ++i)
        params[m.param_names[i]] = m.param_values[i];
    }
  }
  const ProgramRun replay =
      RunProgram(CanalidProgram() + " replay " + (dir / "run.lcmlog").string(), dir);
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  run.replay_err = replay.err;
  std::istringstream replayed(replay.out);
  while (std::getline(replayed, line)) {
    // The batch models are the lines without an estimator (the online ones say "online").
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_object() && j.contains("model") && !j.contains("estimator")) {
      run.replayed[j.value("model", "")] = j;
    }
  }
  return run;
}

}  // namespace canalid::testing
