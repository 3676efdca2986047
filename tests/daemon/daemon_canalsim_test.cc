// canalidd end to end against canalsim serve (ASCE test canal 2 behind its Modbus TCP PLC, scaled
// time): each test starts its own simulator on a free port and its own daemon with a
// configuration written from config/canalidd-asce2.toml, waits for the daemon's log lines with
// bounded polls, reads the gate setpoint through a separate Modbus master, and stops everything by
// pid.  The truths: the IDZ reference of pool 2 (domain/README.md: backwater area 34113 m2, delay
// 682 s), the nominal setpoint read from the PLC before the daemon ran, and the exit codes.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <canalid/experiment_state_t.hpp>
#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include "tests/sim/serve_process.h"
#include "tests/support/child_process.h"
#include "tests/support/daemon_experiment_run.h"
#include "tests/support/json_after.h"
#include "tests/support/private_network.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

// The TOML line `key = value` (value as written in the file).
std::string KeyLine(const std::string& key, const std::string& value) {
  return key + " = " + value;
}

namespace fs = std::filesystem;

constexpr int kSetpointAddress = 300;  // holding float block, pool record 0, field 0 (abcd)
constexpr int kDropFault = 12;
constexpr int kExceptionFault = 11;
constexpr int kSpikeRecords = 14;
constexpr int kSpikeAmplitude = 15;
constexpr int kSpikePeriod = 16;
constexpr double kTimeScale = 600.0;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A fresh folder per test under the build tree.
fs::path TestDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "daemon_canalsim" /
                 (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  // The state directory exists before the daemon starts, as systemd's StateDirectory= makes it
  // (the store refuses to save into a missing one).
  fs::create_directories(dir / "state");
  return dir;
}

// config/canalidd-asce2.toml with whole lines `key = ...` replaced and, when `experiment` is not
// empty, everything from the first [[experiment]] on replaced by `experiment`.
std::string WriteConfig(const fs::path& path,
                        const std::vector<std::pair<std::string, std::string>>& keys,
                        const std::string& experiment = "") {
  std::string text = ReadText(SourcePath("config/canalidd-asce2.toml"));
  if (!experiment.empty()) text = text.substr(0, text.find("[[experiment]]")) + experiment;
  std::istringstream in(text);
  std::ostringstream out;
  std::string line;
  int replaced = 0;
  while (std::getline(in, line)) {
    for (const auto& [key, value] : keys) {
      if (line.rfind(KeyLine(key, ""), 0) == 0) {
        line = KeyLine(key, value);
        ++replaced;
      }
    }
    out << line << "\n";
  }
  EXPECT_EQ(replaced, static_cast<int>(keys.size())) << "a key to replace is missing";
  std::ofstream(path) << out.str();
  return path.string();
}

std::vector<std::pair<std::string, std::string>> BaseKeys(int port, const fs::path& dir) {
  return {{"port", std::to_string(port)},
          {"state_directory", "\"" + (dir / "state").string() + "\""},
          {"time_scale", "600.0"}};
}

// A short explicit experiment: Ts = 0.1 wall s x 600 = 60 plant s; each PRBS bit held 2 samples,
// order `order`: (2^order - 1) x 2 samples of excitation.
std::string ExplicitExperiment(double amplitude_m, int order, const std::string& start = "on_start",
                               const std::string& commands = "[commands]\nenabled = false\n") {
  std::ostringstream s;
  s << "[[experiment]]\nname = \"pool2_short\"\nreach = \"pool2\"\nmode = \"explicit\"\n"
    << "amplitude = " << amplitude_m << "\nclock_period_s = 120.0\norder = " << order
    << "\nseed = 1\nsettle_s = 0.0\nstart = \"" << start
    << "\"\nmax_invalid_samples = 3\n"
    // 0.5 wall s: this machine is shared while tests run, a late poll is no fault to test here.
    << "max_sample_gap_periods = 5.0\n\n"
    << commands;
  return s.str();
}

double ReadSetpoint(Master& master) { return master.HoldingFloatAbcd(kSetpointAddress); }

// Every number of `expected` (recursively) equals the one at the same place in `actual` to
// `relative`; returns the first difference, empty when none.
std::string JsonNumbersDiffer(const nlohmann::json& expected, const nlohmann::json& actual,
                              double relative, const std::string& at = "") {
  if (expected.is_number()) {
    if (!actual.is_number()) return at + ": not a number in the replay";
    const double e = expected.get<double>(), a = actual.get<double>();
    if (std::abs(a - e) > relative * std::max(std::abs(e), 1e-300) && a != e)
      return at + ": live " + std::to_string(e) + ", replay " + std::to_string(a);
    return {};
  }
  if (expected.is_object() || expected.is_array()) {
    if (actual.type() != expected.type() || actual.size() != expected.size())
      return at + ": differs in shape";
    for (auto it = expected.begin(); it != expected.end(); ++it) {
      const std::string key =
          expected.is_object() ? it.key() : std::to_string(it - expected.begin());
      const nlohmann::json& other =
          expected.is_object() ? actual.at(it.key())
                               : actual.at(static_cast<std::size_t>(it - expected.begin()));
      std::string path = at;
      path += "/";
      path += key;
      std::string d = JsonNumbersDiffer(*it, other, relative, path);
      if (!d.empty()) return d;
    }
    return {};
  }
  return expected == actual ? std::string()
                            : at + ": live " + expected.dump() + ", replay " + actual.dump();
}

struct Canal {
  explicit Canal(const fs::path& dir, const std::vector<std::string>& extra = {})
      : serve(Args(extra), dir / "canalsim.err"), master(serve.port(), 2.0) {}
  static std::vector<std::string> Args(const std::vector<std::string>& extra) {
    std::vector<std::string> a = {"--canal",      SourcePath("config/sim/asce-canal2.toml"),
                                  "--plc",        SourcePath("config/sim/plc/asce2.toml"),
                                  "--time-scale", "600"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  ServeProcess serve;
  Master master;
};

std::unique_ptr<ChildProcess> StartDaemon(const fs::path& dir, const std::string& config,
                                          const std::string& log_name = "canalidd.log",
                                          const std::string& lcm_log = "run.lcmlog") {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{DaemonProgram(), "--config", config},
      std::vector<std::string>{"LCM_DEFAULT_URL=file://" + (dir / lcm_log).string() + "?mode=w"},
      dir / log_name);
}

std::size_t Position(const ChildProcess& p, const std::string& line) {
  return p.output().find(line);
}

// A daemon on `canal`'s pool 2 with the base keys, `key = value` and a 126-sample PRBS experiment
// (amplitude 0.05 m, order 6) that starts at once, run until it logs the pool identified; the
// config's path is in `config`. Fails the test (and returns the daemon) when it does not.
std::unique_ptr<ChildProcess> RunPool2Experiment(const fs::path& dir, const Canal& canal,
                                                 const std::string& key, const std::string& value,
                                                 std::string* config) {
  auto keys = BaseKeys(canal.serve.port(), dir);
  keys.emplace_back(key, value);
  *config = WriteConfig(dir / "canalidd.toml", keys, ExplicitExperiment(0.05, 6));
  auto daemon = StartDaemon(dir, *config);
  // 126 samples of excitation at 10 samples per wall second.
  EXPECT_FALSE(daemon->WaitForLine("reach pool2: identified ", 60000).empty()) << daemon->output();
  return daemon;
}

// 1. The demo's designed experiment: the IDZ model it prints near the IDZ reference (pool 2 ends at
// a fixed gate; the default closed-loop setting), nominal restored on SIGTERM, `canalid replay`
// of the run's LCM log (file://) ends on the model identified live, the models resumed by the
// next daemon.
TEST(DaemonCanalsim, DesignedExperimentIdentifiesRestoresReplaysAndResumes) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  const std::string config = WriteConfig(dir / "canalidd.toml", BaseKeys(canal.serve.port(), dir));
  auto daemon = StartDaemon(dir, config);
  // 378 samples of excitation at 10 samples per wall second plus settling: about 40 s.
  const std::string line = daemon->WaitForLine("reach pool2: identified {", 120000);
  ASSERT_FALSE(line.empty()) << daemon->output();
  const nlohmann::json model = JsonAfter(line, "identified ");
  ASSERT_TRUE(model.is_object()) << line;
  const double area = model.at("area_m2").get<double>();
  const std::string idz_line = daemon->WaitForLine("reach pool2: identified idz ", 20000);
  ASSERT_FALSE(idz_line.empty()) << daemon->output();
  const nlohmann::json idz = JsonAfter(idz_line, "identified idz ");
  ASSERT_TRUE(idz.is_object()) << idz_line;
  // The bounds for the demo's printed model: the IDZ reference is a linearisation of the
  // Saint-Venant plant canalsim runs, and the delay is quantised to Ts = 60 s (measured: 32994
  // m2, -3.3 %, and 660 s). The ID model's three-step estimate (22926 m2) is not asserted: on a
  // gate-ended pool the ID structure lacks the outflow's direct term (docs/closed-loop.md).
  EXPECT_EQ(idz.value("p22_source", ""), "prior") << idz_line;
  EXPECT_NEAR(idz.at("area_m2").get<double>(), 34113.0, 0.1 * 34113.0) << idz_line;
  EXPECT_GE(idz.at("delay_s").get<double>(), 0.8 * 682.0) << idz_line;
  EXPECT_LE(idz.at("delay_s").get<double>(), 1.2 * 682.0) << idz_line;

  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  // Read at once: the PLC's own watchdog would also put the gate back, but only after 0.5 s.
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  EXPECT_NE(daemon->output().find("stopped"), std::string::npos) << daemon->output();

  // Replay from the log alone (the configuration comes from the log): the last line is the final
  // model, equal to the live one to 1e-9 relative (the same code on the same samples; in fact
  // bit-identical, but the promise is 1e-9).
  const ProgramRun replay =
      RunProgram(CanalidProgram() + " replay " + (dir / "run.lcmlog").string(), dir);
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  const std::string last = replay.out.substr(replay.out.rfind('\n', replay.out.size() - 2) + 1);
  const nlohmann::json replayed = nlohmann::json::parse(last, nullptr, false);
  ASSERT_TRUE(replayed.is_object()) << replay.out;
  EXPECT_EQ(JsonNumbersDiffer(model, replayed, 1e-9), "") << line << "\n" << last;

  auto again = StartDaemon(dir, config, "canalidd-2.log", "run-2.lcmlog");
  const std::string resumed = again->WaitForLine("resumed the persisted id model", 20000);
  ASSERT_FALSE(resumed.empty()) << again->output();
  const nlohmann::json persisted = JsonAfter(resumed, "model ");
  ASSERT_TRUE(persisted.is_object()) << resumed;
  EXPECT_DOUBLE_EQ(persisted.at("area_m2").get<double>(), area);
  const std::string resumed_idz = again->WaitForLine("resumed the persisted idz model", 20000);
  ASSERT_FALSE(resumed_idz.empty()) << again->output();
  EXPECT_EQ(JsonNumbersDiffer(idz, JsonAfter(resumed_idz, "model "), 0.0), "");
  EXPECT_EQ(again->Stop(SIGTERM), 0) << again->output();
}

// The two-structure experiment of config/canalidd-asce2-two-structures.toml (appended to the
// demo's file, its experiment started at once instead of the demo's): the gate's designed PRBS
// with the offtake's uncorrelated one, each reach's actuator with its own limits, guard and
// restore (core/reach/joint_experiments.h). The truths: the published IDZ table for pool 2 at
// 10 m3/s (34113 m2, 682 s, p22 0.0216 s/m2), the offtake's nominal read from canalsim before the
// daemon ran, and `canalid replay`'s models from the log.
constexpr int kOfftakeAddress = 306;  // holding float block, pool record 1, field 1

// The demo's configuration with config/canalidd-asce2-two-structures.toml appended, the
// two-structure experiment started at once instead of the demo's, and `replace` (whole text,
// e.g. a key of the offtake's reach) swapped in; returns the file's path.
std::string WriteTwoStructureConfig(const fs::path& dir, int port,
                                    const std::pair<std::string, std::string>& replace = {}) {
  std::string text = ReadText(WriteConfig(dir / "canalidd.toml", BaseKeys(port, dir)));
  std::string addon = ReadText(SourcePath("config/canalidd-asce2-two-structures.toml"));
  if (!replace.first.empty()) {
    const std::size_t at = addon.find(replace.first);
    EXPECT_NE(at, std::string::npos) << replace.first;
    if (at != std::string::npos) addon.replace(at, replace.first.size(), replace.second);
  }
  text += "\n" + addon;
  auto swap_start = [&](const std::string& experiment, const std::string& from,
                        const std::string& to) {
    const std::size_t at = text.find("name = \"" + experiment + "\"\nreach");
    EXPECT_NE(at, std::string::npos) << experiment;
    const std::size_t start = text.find("start = \"" + from + "\"", at);
    EXPECT_NE(start, std::string::npos) << experiment;
    if (start != std::string::npos) text.replace(start, from.size() + 10, "start = \"" + to + "\"");
  };
  swap_start("pool2_prbs", "on_start", "manual");
  swap_start("pool2_two_structures", "manual", "on_start");
  std::ofstream(dir / "canalidd.toml") << text;
  return (dir / "canalidd.toml").string();
}

TEST(DaemonCanalsim, TwoStructureExperimentFitsP22FromTheDataAndRestoresBoth) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double gate_nominal = ReadSetpoint(canal.master);
  const double offtake_nominal = canal.master.HoldingFloatAbcd(kOfftakeAddress);
  ASSERT_NEAR(offtake_nominal, 1.0, 1e-6);  // the canal file's offtake of pool 2
  auto daemon = StartDaemon(dir, WriteTwoStructureConfig(dir, canal.serve.port()));
  const std::string idz_line = daemon->WaitForLine("reach pool2: identified idz ", 120000);
  ASSERT_FALSE(idz_line.empty()) << daemon->output();
  const nlohmann::json idz = JsonAfter(idz_line, "identified idz ");
  ASSERT_TRUE(idz.is_object()) << idz_line;
  // The offtake started with the gate's experiment and ended with it (done, not aborted) when
  // the gate's excitation ended.
  const std::string& log = daemon->output();
  const std::size_t started = log.find(
      "reach pool2_offtake: joint experiment: started with experiment 'pool2_two_structures' of "
      "reach pool2");
  const std::size_t identifying = log.find("reach pool2: experiment identifying");
  const std::size_t ended =
      log.find("reach pool2_offtake: experiment done (ended with its joint experiment)");
  ASSERT_NE(started, std::string::npos) << log;
  ASSERT_NE(identifying, std::string::npos) << log;
  ASSERT_NE(ended, std::string::npos) << log;
  EXPECT_LT(started, identifying);
  EXPECT_LT(identifying, ended);
  EXPECT_EQ(log.find("experiment aborted"), std::string::npos) << log;
  ASSERT_FALSE(daemon->WaitForLine("reach pool2_offtake: nominal setpoint", 10000, ended).empty())
      << log;

  // The tolerances: p22 from the data and within 25 %, p21 within 25 %, the area within
  // 10 %, the delay within 0.8-1.2 x. Measured (four runs, seeds 77 and 99, offtake clock 300 and
  // 420 s): p22 -2.8 to +0.2 %, area +0.1 to +2.1 %, delay 660 s; p21 -9.2 and -9.1 % (two runs of
  // the IDZ fit's zero-order-hold equation; -17 to -19 % with the ID regression's sum).
  std::printf("two structures, idz: area %+.1f %%, delay %.0f s, p21 %+.1f %%, p22 %+.1f %%\n",
              100.0 * (idz.at("area_m2").get<double>() / 34113.0 - 1.0),
              idz.at("delay_s").get<double>(),
              100.0 * (idz.at("p21_s_per_m2").get<double>() / 0.0185 - 1.0),
              100.0 * (idz.at("p22_s_per_m2").get<double>() / 0.0216 - 1.0));
  EXPECT_EQ(idz.value("p22_source", ""), "data") << idz_line;
  EXPECT_NEAR(idz.at("p22_s_per_m2").get<double>(), 0.0216, 0.25 * 0.0216) << idz_line;
  EXPECT_NEAR(idz.at("p21_s_per_m2").get<double>(), 0.0185, 0.25 * 0.0185) << idz_line;
  EXPECT_NEAR(idz.at("area_m2").get<double>(), 34113.0, 0.10 * 34113.0) << idz_line;
  EXPECT_GE(idz.at("delay_s").get<double>(), 0.8 * 682.0) << idz_line;
  EXPECT_LE(idz.at("delay_s").get<double>(), 1.2 * 682.0) << idz_line;

  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), gate_nominal, 1e-4);
  EXPECT_NEAR(canal.master.HoldingFloatAbcd(kOfftakeAddress), offtake_nominal, 1e-6);

  // What the offtake did, from the samples the daemon logged: its PRBS (nominal +- 0.2 m3/s)
  // while the gate's experiment ran (its return to nominal is the read above: the daemon may stop
  // before it polls again).
  const ProgramRun exported =
      RunProgram(CanalidProgram() + " export " + (dir / "run.lcmlog").string() + " --out " +
                     (dir / "csv").string() + " --reach pool2_offtake",
                 dir);
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  std::istringstream rows(ReadText(dir / "csv" / "pool2_offtake.csv"));
  std::string row;
  std::getline(rows, row);
  const std::size_t column = static_cast<std::size_t>(std::count(
      row.begin(), row.begin() + static_cast<std::ptrdiff_t>(row.find("offtake2_setpoint")), ','));
  int low = 0, high = 0, other = 0;
  while (std::getline(rows, row)) {
    std::istringstream cells(row);
    std::string cell;
    for (std::size_t i = 0; i <= column; ++i) std::getline(cells, cell, ',');
    const double value = std::stod(cell);
    low += std::abs(value - (offtake_nominal - 0.2)) < 1e-4 ? 1 : 0;
    high += std::abs(value - (offtake_nominal + 0.2)) < 1e-4 ? 1 : 0;
    other += std::abs(value - offtake_nominal) > 0.2 + 1e-4 ? 1 : 0;
  }
  // 378 samples of excitation, about half at each level, none outside them.
  EXPECT_GT(low, 150);
  EXPECT_GT(high, 150);
  EXPECT_EQ(other, 0);

  // The replay runs the same joint rules on the same samples: the same idz model, no divergence.
  const ProgramRun replay =
      RunProgram(CanalidProgram() + " replay " + (dir / "run.lcmlog").string(), dir);
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(replay.err.find("diverges"), std::string::npos) << replay.err;
  std::istringstream lines(replay.out);
  std::string line;
  std::optional<nlohmann::json> replayed;
  while (std::getline(lines, line)) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_object() && j.value("model", "") == "idz") replayed = j;
  }
  ASSERT_TRUE(replayed.has_value()) << replay.out;
  EXPECT_EQ(JsonNumbersDiffer(idz, *replayed, 1e-9), "") << idz_line << "\n" << replayed->dump();

  // On the bus, the offtake's experiment ended done with the gate's, and says so.
  std::vector<std::pair<int, std::string>> offtake_states;
  lcm::LogFile bus((dir / "run.lcmlog").string(), "r");
  while (const lcm::LogEvent* e = bus.readNextEvent()) {
    if (e->channel != "CANALID_ASCE2_EXPERIMENT_pool2_offtake") continue;
    canalid::experiment_state_t m;
    if (m.decode(e->data, 0, e->datalen) != e->datalen) continue;
    offtake_states.emplace_back(m.state, m.reason);
  }
  ASSERT_FALSE(offtake_states.empty());
  EXPECT_EQ(offtake_states.back(), std::make_pair(+canalid::experiment_state_t::STATE_DONE,
                                                  std::string("ended with its joint experiment")));
  // A replay of the offtake alone does not run its leader: the live end is no divergence there
  // (HasOtherMember is false), so nothing is said.
  const ProgramRun alone = RunProgram(
      CanalidProgram() + " replay " + (dir / "run.lcmlog").string() + " --reach pool2_offtake",
      dir);
  EXPECT_EQ(alone.err.find("diverges"), std::string::npos) << alone.err;
  EXPECT_NE(alone.err.find("reach pool2_offtake is configured with none"), std::string::npos)
      << alone.err;
  // Re-identified with the gate settling 5 samples longer, the replay's joint rules have not
  // ended the offtake's experiment when the live one ends: it says the replay diverges there.
  std::string longer = ReadText(dir / "canalidd.toml");
  const std::size_t joint_at = longer.find("name = \"pool2_two_structures\"");
  const std::size_t settle_at = longer.find("settle_s = 600.0", joint_at);
  ASSERT_NE(settle_at, std::string::npos);
  longer.replace(settle_at, 16, "settle_s = 900.0");
  std::ofstream(dir / "longer.toml") << longer;
  const ProgramRun diverged =
      RunProgram(CanalidProgram() + " replay " + (dir / "run.lcmlog").string() + " --config " +
                     (dir / "longer.toml").string(),
                 dir);
  EXPECT_NE(diverged.err.find("reach pool2_offtake: the live experiment ended with its joint "
                              "experiment where the replay's did not: the replay diverges"),
            std::string::npos)
      << diverged.err;
  // The leader too: its live excitation ended 5 samples before the replay's, said once although
  // the daemon publishes the state again with its health.
  const std::string leader_diverges =
      "reach pool2: the live experiment ended its excitation where the replay's still runs: the "
      "replay diverges";
  const std::size_t first = diverged.err.find(leader_diverges);
  EXPECT_NE(first, std::string::npos) << diverged.err;
  EXPECT_EQ(diverged.err.find(leader_diverges, first + 1), std::string::npos) << diverged.err;
}

// The same experiment with the offtake's level band narrowed to 5 mm above the pool's level at
// rest: the offtake's experiment aborts out of its band once the PRBS moves the level, which
// stops the gate's (its joint experiment) at the same poll; each actuator is back at its nominal,
// confirmed by the PLC, and no record is identified.
TEST(DaemonCanalsim, TwoStructureExperimentStopsWholeWhenThePartnerAborts) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double gate_nominal = ReadSetpoint(canal.master);
  const double offtake_nominal = canal.master.HoldingFloatAbcd(kOfftakeAddress);
  auto daemon =
      StartDaemon(dir, WriteTwoStructureConfig(dir, canal.serve.port(),
                                               {"level_max_m = 2.3\nonline_models = []",
                                                "level_max_m = 2.105\nonline_models = []"}));
  const std::string aborted =
      daemon->WaitForLine("reach pool2_offtake: experiment aborted (level out of band)", 60000);
  ASSERT_FALSE(aborted.empty()) << daemon->output();
  const std::size_t at = Position(*daemon, aborted);
  const std::string joint = daemon->WaitForLine(
      "reach pool2: joint experiment: experiment 'pool2_offtake_prbs' of reach pool2_offtake "
      "aborted (level out of band)",
      10000, at);
  ASSERT_FALSE(joint.empty()) << daemon->output();
  ASSERT_FALSE(
      daemon
          ->WaitForLine("reach pool2: experiment aborted (stopped with its joint experiment)",
                        10000, at)
          .empty())
      << daemon->output();
  ASSERT_FALSE(daemon->WaitForLine("reach pool2: nominal setpoint", 10000, at).empty())
      << daemon->output();
  ASSERT_FALSE(daemon->WaitForLine("reach pool2_offtake: nominal setpoint", 10000, at).empty())
      << daemon->output();
  // Restores confirmed by the PLC: what it holds now.
  EXPECT_NEAR(ReadSetpoint(canal.master), gate_nominal, 1e-4);
  EXPECT_NEAR(canal.master.HoldingFloatAbcd(kOfftakeAddress), offtake_nominal, 1e-6);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_EQ(daemon->output().find("reach pool2: identified"), std::string::npos)
      << daemon->output();
  // Replayed whole, and for the gate's reach alone (its stop then comes from the log's message):
  // the same aborts, no divergence.
  for (const std::string reach : {"", " --reach pool2"}) {
    const ProgramRun replay =
        RunProgram(CanalidProgram() + " replay " + (dir / "run.lcmlog").string() + reach, dir);
    EXPECT_EQ(replay.err.find("diverges"), std::string::npos) << reach << "\n" << replay.err;
    EXPECT_NE(replay.err.find("samples of"), std::string::npos) << replay.err;
  }
  // The offtake's reach alone has nothing to report, and says why.
  const ProgramRun offtake = RunProgram(
      CanalidProgram() + " replay " + (dir / "run.lcmlog").string() + " --reach pool2_offtake",
      dir);
  EXPECT_EQ(offtake.exit_code, 1);
  EXPECT_NE(offtake.err.find("no model: reach pool2_offtake is configured with none"),
            std::string::npos)
      << offtake.err;
}

// The demo's designed experiment on pool 2 (closed loop: a fixed gate ends the pool), with the
// online id and idz banks: at the end of the experiment each online bank's delay is its batch
// fit's (the banks choose by each candidate's least-squares loss, which with lambda = 1 is the
// batch scan's; the bank also sees the samples before the experiment, so this is measured, not
// exact by construction).  Measured in this test: online id and idz 660 s, as both batch fits;
// the online idz area 32954 m2 against the batch's 33011 (IDZ reference 34113).  The id banks'
// areas are different estimators in closed loop and are compared with what each estimates: the
// online id is the open-loop least squares (39632 m2), as the batch's
// `cross_check.open_loop_area_m2` (39714 m2), while the batch id reports the three-step
// estimate (22939 m2; docs/closed-loop.md).
TEST(DaemonCanalsim, Pool2OnlineBanksChooseTheBatchDelays) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const std::string config =
      RewriteDaemonConfig(SourcePath("config/canalidd-asce2.toml"),
                          {{"port", std::to_string(canal.serve.port())},
                           {"state_directory", "\"" + (dir / "state").string() + "\""},
                           {"online_models", "[\"id\", \"idz\"]"}},
                          "");
  const DaemonExperimentRun run =
      RunDaemonExperiment(dir, config, "pool2", "CANALID_ASCE2_", 120000);
  ASSERT_EQ(run.batch.count("id"), 1U) << run.output;
  ASSERT_EQ(run.batch.count("idz"), 1U) << run.output;
  ASSERT_EQ(run.online.count("id"), 1U);
  ASSERT_EQ(run.online.count("idz"), 1U);
  const nlohmann::json& id = run.batch.at("id");
  const nlohmann::json& idz = run.batch.at("idz");
  const auto& online_id = run.online.at("id");
  const auto& online_idz = run.online.at("idz");
  EXPECT_EQ(online_id.at("delay_s"), id.at("delay_s").get<double>()) << id;
  EXPECT_EQ(online_idz.at("delay_s"), idz.at("delay_s").get<double>()) << idz;
  const double idz_area = idz.at("area_m2").get<double>();
  EXPECT_NEAR(online_idz.at("area_m2"), idz_area, 0.05 * idz_area) << idz;
  EXPECT_NEAR(idz_area, 34113.0, 0.1 * 34113.0) << idz;
  const double open_loop_area = id.at("cross_check").at("open_loop_area_m2").get<double>();
  EXPECT_NEAR(online_id.at("area_m2"), open_loop_area, 0.05 * open_loop_area) << id;
}

// The same in the run's log, dir/run.lcmlog.
std::vector<canalid::model_snapshot_t> ModelMessages(const fs::path& dir,
                                                     const std::string& channel) {
  return ModelMessagesIn(dir / "run.lcmlog", channel);
}

// The last online snapshot the daemon published per model kind (MODEL_<reach> messages of its
// LCM log, estimator not "batch"/"persisted").
std::map<std::string, canalid::model_snapshot_t> LastOnlineModels(const fs::path& dir,
                                                                  const std::string& channel) {
  std::map<std::string, canalid::model_snapshot_t> last;
  for (const canalid::model_snapshot_t& m : ModelMessages(dir, channel)) {
    if (m.estimator != "batch" && m.estimator != "persisted") last[m.model_kind] = m;
  }
  return last;
}

// Every parameter of `live` that `json` has under its name is the same double; returns the first
// difference (empty when none) and counts the parameters compared.
std::string SameParameters(const canalid::model_snapshot_t& live, const nlohmann::json& json,
                           int* compared) {
  *compared = 0;
  for (std::size_t i = 0; i < live.param_names.size(); ++i) {
    const std::string& name = live.param_names[i];
    if (!json.contains(name) || !json[name].is_number()) continue;
    ++*compared;
    if (json[name].get<double>() != live.param_values[i]) {
      std::ostringstream m;
      m.precision(17);
      m << live.model_kind << " " << name << ": live " << live.param_values[i] << ", other "
        << json[name].get<double>();
      return m.str();
    }
  }
  return {};
}

// `canalid replay ARGS LOG`: the last model JSON line of each kind (with `estimator` equal to
// `estimator` when it is not empty); an empty map (and a test failure) when it fails. `err`: its
// standard error.
std::map<std::string, nlohmann::json> ReplayedModelsOf(const fs::path& log, const fs::path& dir,
                                                       const std::string& args,
                                                       const std::string& estimator,
                                                       std::string* err = nullptr) {
  std::map<std::string, nlohmann::json> last;
  const ProgramRun replay =
      RunProgram(CanalidProgram() + " replay " + args + " " + log.string(), dir);
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  if (err != nullptr) *err = replay.err;
  std::istringstream lines(replay.out);
  std::string text;
  while (std::getline(lines, text)) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_object() && (estimator.empty() || j.value("estimator", "") == estimator)) {
      last[j.value("model", "")] = j;
    }
  }
  return last;
}

// The same for the run's log, dir/run.lcmlog.
std::map<std::string, nlohmann::json> ReplayedModels(const fs::path& dir, const std::string& args,
                                                     const std::string& estimator) {
  return ReplayedModelsOf(dir / "run.lcmlog", dir, args, estimator);
}

// Every online kind the daemon runs on pool 2 (id, arx, frac-foptd, idz with the demo file's
// p22 prior, frac-ss, lpv scheduled on the inflow), live over Modbus: the last
// snapshot of each that it published equals, bit for bit, the final one of `canalid replay` of
// its log and that of `canalid identify --online --config` on the record `canalid export` wrote
// (the same registry, settings and samples); each kind was published.
TEST(DaemonCanalsim, EveryOnlineKindIsReproducedByReplayAndIdentify) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  std::string config;
  auto daemon =
      RunPool2Experiment(dir, canal, "online_models",
                         "[\"id\", \"arx\", \"frac-foptd\", \"idz\", \"frac-ss\", \"lpv\"]\n"
                         "lpv_scheduling = \"pool2_inflow\"",
                         &config);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();

  const auto live = LastOnlineModels(dir, "CANALID_ASCE2_MODEL_pool2");
  ASSERT_EQ(live.size(), 6U);
  for (const char* kind : {"id", "arx", "frac-foptd", "idz", "frac-ss", "lpv"}) {
    ASSERT_EQ(live.count(kind), 1U) << kind;
    EXPECT_GT(live.at(kind).samples_used, 100) << kind;
  }
  EXPECT_EQ(live.at("frac-foptd").num_params, 6);
  EXPECT_EQ(live.at("frac-ss").num_params, 2 + 4 + 3 + 2);  // q = 2: a1..a4, c1..c3
  EXPECT_EQ(live.at("lpv").num_params, 1 + 6 + 2);          // na = nb = 1, quadratics
  // idz: the id bank's parameters, the wave front, and the prior held (the demo file's).
  const canalid::model_snapshot_t& idz = live.at("idz");
  ASSERT_EQ(idz.num_params, 7);
  EXPECT_EQ(idz.param_names[6], "p22_s_per_m2");
  EXPECT_DOUBLE_EQ(idz.param_values[6], 0.01334);

  // Replay, a snapshot after every sample: the last of each kind is the final state.
  std::map<std::string, nlohmann::json> replayed =
      ReplayedModels(dir, "--json --snapshot-every 1", "online");
  for (const auto& [kind, model] : live) {
    ASSERT_EQ(replayed.count(kind), 1U) << kind;
    int compared = 0;
    EXPECT_EQ(SameParameters(model, replayed[kind], &compared), "");
    EXPECT_GE(compared, 4) << kind;
  }

  const ProgramRun exported =
      RunProgram(CanalidProgram() + " export " + (dir / "run.lcmlog").string() + " --out " +
                     (dir / "export").string(),
                 dir);
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const std::string identify_online = CanalidProgram() + " identify --online --config " + config +
                                      " --reach pool2 --input " +
                                      (dir / "export" / "pool2.csv").string() + " --model ";
  for (const auto& [kind, model] : live) {
    const ProgramRun identify = RunProgram(identify_online + kind, dir);
    ASSERT_EQ(identify.exit_code, 0) << kind << ": " << identify.err;
    const nlohmann::json json = nlohmann::json::parse(identify.out, nullptr, false);
    ASSERT_TRUE(json.is_object()) << identify.out;
    int compared = 0;
    EXPECT_EQ(SameParameters(model, json, &compared), "");
    EXPECT_EQ(compared, model.num_params) << kind;
    // The P0 it used, the configuration's default (docs/configuration.md).
    EXPECT_EQ(json.value("initial_covariance", 0.0), 1e10) << kind;
  }

  // `canalid report --input LOG` draws every online kind's trajectory with its +-2 sigma band:
  // one figure per kind, whose data's last row is the last snapshot published.
  const ProgramRun report =
      RunProgram(CanalidProgram() + " report --input " + (dir / "run.lcmlog").string() +
                     " --model id --out " + (dir / "report").string(),
                 dir);
  ASSERT_EQ(report.exit_code, 0) << report.err;
  const std::string html = ReadText(dir / "report" / "index.html");
  for (const auto& [kind, model] : live) {
    const std::string image = "online_" + kind + ".png";
    EXPECT_GT(fs::file_size(dir / "report" / image), 1000U) << kind;
    EXPECT_NE(html.find(image), std::string::npos) << kind;
    std::ifstream data(dir / "report" / "gnuplot" / ("online_" + kind + ".dat"));
    std::string row, last;
    while (std::getline(data, row)) last = row;
    std::istringstream cells(last);
    std::vector<double> numbers;
    for (std::string cell; cells >> cell;) numbers.push_back(std::stod(cell));
    // time, then (value, value - 2 sigma, value + 2 sigma) per parameter, operating points left
    // out: the first parameter is the snapshot's first.
    ASSERT_GE(numbers.size(), 4U) << last;
    EXPECT_NEAR(numbers[1], model.param_values[0], 1e-9 * std::abs(model.param_values[0])) << kind;
    if (std::isfinite(model.param_std_devs[1])) {
      EXPECT_NEAR(numbers[6] - numbers[5], 4.0 * model.param_std_devs[1],
                  1e-6 * std::abs(model.param_std_devs[1]) + 1e-9 * std::abs(model.param_values[1]))
          << kind;
    }
  }
}

// model_publish_period_s = 600 (10 samples of 60 s): each online model is published on every
// tenth sample, not on every one.
TEST(DaemonCanalsim, ModelPublishPeriodThinsTheOnlineModels) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  std::string config;
  auto daemon = RunPool2Experiment(dir, canal, "online_models",
                                   "[\"id\", \"arx\"]\nmodel_publish_period_s = 600.0", &config);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  std::map<std::string, std::vector<std::int64_t>> updates;  // kind -> samples_used published
  for (const canalid::model_snapshot_t& m : ModelMessages(dir, "CANALID_ASCE2_MODEL_pool2")) {
    if (m.estimator == "rls-bank") updates[m.model_kind].push_back(m.samples_used);
  }
  for (const char* kind : {"id", "arx"}) {
    const std::vector<std::int64_t>& u = updates[kind];
    ASSERT_GE(u.size(), 5U) << kind;
    for (std::size_t i = 1; i < u.size(); ++i) {
      // Every sample updates the estimators here: ten updates between two publications.
      EXPECT_EQ(u[i] - u[i - 1], 10) << kind << " message " << i;
    }
  }
}

// batch_models = ["id", "idz", "foptd", "frac-foptd", "soptd", "arx"] on pool 2, live: at the end
// of the experiment the idz model and each process model are logged, published on MODEL_pool2 with
// estimator "batch" and persisted when inside their bounds; `canalid replay` of the log gives the
// same models (the same fits on the same record); the next daemon resumes the persisted ones from
// the state directory.
TEST(DaemonCanalsim, BatchProcessModelsArePublishedPersistedReplayedAndResumed) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  std::string config;
  auto daemon = RunPool2Experiment(
      dir, canal, "batch_models",
      "[\"id\", \"idz\", \"foptd\", \"frac-foptd\", \"soptd\", \"arx\", \"frac-ss\"]", &config);
  ASSERT_FALSE(::testing::Test::HasFailure());
  std::map<std::string, nlohmann::json> live;  // kind -> the JSON logged
  for (const char* kind : {"idz", "foptd", "frac-foptd", "soptd", "arx", "frac-ss"}) {
    const std::string line =
        daemon->WaitForLine("reach pool2: identified " + std::string(kind) + " ", 20000);
    ASSERT_FALSE(line.empty()) << kind << "\n" << daemon->output();
    live[kind] = JsonAfter(line, "identified " + std::string(kind) + " ");
    ASSERT_TRUE(live[kind].is_object()) << line;
    EXPECT_EQ(live[kind].value("model", ""), kind);
    if (std::string(kind) == "idz") {
      // Pool 2 ends at a fixed gate: p22 is the configured prior, the area that of the pool.
      EXPECT_EQ(live[kind].value("p22_source", ""), "prior") << line;
      EXPECT_GT(live[kind].at("area_m2").get<double>(), 0.0) << line;
    } else if (std::string(kind) == "arx") {
      // The reach's orders (arx_na = arx_nb = 2 by default), a delay inside the id bank's range.
      EXPECT_EQ(live[kind].at("a").size(), 2U) << line;
      EXPECT_EQ(live[kind].at("b_coeffs").at(0).size(), 2U) << line;
      EXPECT_GT(live[kind].at("delay_s").get<double>(), 0.0) << line;
    } else if (std::string(kind) == "frac-ss") {
      // The reach's frac_ss_q (2 by default): n = 4 states.
      EXPECT_EQ(live[kind].at("q"), 2) << line;
      EXPECT_EQ(live[kind].at("A").size(), 4U) << line;
    } else {
      EXPECT_GT(live[kind].at("gain").get<double>(), 0.0) << line;  // the gate raises the level
    }
  }
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();

  // Published with estimator "batch", one message per kind.
  std::map<std::string, canalid::model_snapshot_t> published;
  for (const canalid::model_snapshot_t& m : ModelMessages(dir, "CANALID_ASCE2_MODEL_pool2")) {
    if (m.estimator == "batch") published[m.model_kind] = m;
  }
  for (const auto& [kind, json] : live) {
    ASSERT_EQ(published.count(kind), 1U) << kind;
    int compared = 0;
    EXPECT_EQ(SameParameters(published[kind], json, &compared), "");
    if (kind == "arx") {
      // Its coefficients are arrays in the JSON, a1, a2, b1, b2 in the snapshot.
      nlohmann::json coefficients;
      for (std::size_t j = 0; j < 2; ++j) {
        coefficients["a" + std::to_string(j + 1)] = json.at("a").at(j);
        coefficients["b" + std::to_string(j + 1)] = json.at("b_coeffs").at(0).at(j);
      }
      int coefficients_compared = 0;
      EXPECT_EQ(SameParameters(published[kind], coefficients, &coefficients_compared), "");
      EXPECT_EQ(coefficients_compared, 4);
      compared += coefficients_compared;
    }
    if (kind == "soptd") {
      // Its two time constants are an array in the JSON, two parameters in the snapshot.
      nlohmann::json lags;
      lags["time_constant_1_s"] = json.at("time_constants_s").at(0);
      lags["time_constant_2_s"] = json.at("time_constants_s").at(1);
      int lags_compared = 0;
      EXPECT_EQ(SameParameters(published[kind], lags, &lags_compared), "");
      EXPECT_EQ(lags_compared, 2);
      compared += lags_compared;
    }
    if (kind == "frac-ss") {
      // Its coefficients come from the companion form: A's last row -[a4..a1], C [1, c1..c3].
      nlohmann::json coefficients;
      for (std::size_t i = 1; i <= 4; ++i) {
        coefficients["a" + std::to_string(i)] = -json.at("A").at(3).at(4 - i).get<double>();
      }
      for (std::size_t i = 1; i <= 3; ++i)
        coefficients["c" + std::to_string(i)] = json.at("C").at(i);
      int coefficients_compared = 0;
      EXPECT_EQ(SameParameters(published[kind], coefficients, &coefficients_compared), "");
      EXPECT_EQ(coefficients_compared, 7);
      compared += coefficients_compared;
    }
    // The rest point the model's deviations are taken from, named as the online process kinds
    // name their operating point (idz is not a process model).
    if (kind == "idz") continue;
    nlohmann::json rest_point;
    rest_point["input_operating_point"] = json.at("input_offset");
    rest_point["level_operating_point_m"] = json.at("output_offset");
    int rest_compared = 0;
    EXPECT_EQ(SameParameters(published[kind], rest_point, &rest_compared), "");
    EXPECT_EQ(rest_compared, 2) << kind;
    EXPECT_GE(compared, 3) << kind;
    EXPECT_TRUE(fs::exists(dir / "state" / ("pool2." + kind + ".json"))) << kind;
  }

  // Replay: the final models include each process model, equal to the live one.
  std::map<std::string, nlohmann::json> replayed = ReplayedModels(dir, "", "");
  for (const auto& [kind, json] : live) {
    ASSERT_EQ(replayed.count(kind), 1U) << kind;
    EXPECT_EQ(JsonNumbersDiffer(json, replayed[kind], 1e-9), "") << kind;
  }

  auto again = StartDaemon(dir, config, "canalidd-2.log", "run-2.lcmlog");
  for (const auto& [kind, json] : live) {
    const std::string resumed =
        again->WaitForLine("resumed the persisted " + kind + " model", 20000);
    ASSERT_FALSE(resumed.empty()) << again->output();
    EXPECT_EQ(JsonNumbersDiffer(json, JsonAfter(resumed, "model "), 0.0), "") << kind;
  }
  EXPECT_EQ(again->Stop(SIGTERM), 0) << again->output();

  // batch_models without the process kinds: their files are no longer the reach's models (idz
  // stays: the demo's file gives it a p22 prior).
  auto id_only_keys = BaseKeys(canal.serve.port(), dir);
  id_only_keys.emplace_back("batch_models", "[\"id\", \"idz\"]");
  const std::string id_only =
      WriteConfig(dir / "canalidd-id.toml", id_only_keys, ExplicitExperiment(0.05, 6, "manual"));
  auto third = StartDaemon(dir, id_only, "canalidd-3.log", "run-3.lcmlog");
  EXPECT_FALSE(
      third->WaitForLine("kind frac-foptd is not in the reach's batch_models; ignored", 20000)
          .empty())
      << third->output();
  EXPECT_EQ(third->output().find("resumed the persisted foptd"), std::string::npos);
  EXPECT_EQ(third->Stop(SIGTERM), 0) << third->output();
}

// 2. A level band the excitation has to leave: the experiment aborts and the nominal comes back.
TEST(DaemonCanalsim, LevelOutOfBandAbortsAndRestoresNominal) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  auto keys = BaseKeys(canal.serve.port(), dir);
  keys.emplace_back("level_max_m", "2.101");
  // A large opening step (0.3 m) raises pool 2 well above 2.101 m within a few samples.
  const std::string config = WriteConfig(dir / "canalidd.toml", keys, ExplicitExperiment(0.3, 6));
  auto daemon = StartDaemon(dir, config);
  const std::string abort = daemon->WaitForLine("experiment aborted (level out of band)", 30000);
  ASSERT_FALSE(abort.empty()) << daemon->output();
  const std::size_t at = Position(*daemon, abort);
  ASSERT_FALSE(daemon->WaitForLine(" restored", 10000, at).empty()) << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
}

// 3. SIGTERM while the PRBS moves the gate: exit 0, the nominal setpoint is back.
TEST(DaemonCanalsim, SigtermDuringExcitationRestoresNominal) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  const std::string config =
      WriteConfig(dir / "canalidd.toml", BaseKeys(canal.serve.port(), dir),
                  ExplicitExperiment(0.05, 7));  // 254 samples: 25 s, never reached
  auto daemon = StartDaemon(dir, config);
  ASSERT_FALSE(daemon->WaitForLine("experiment exciting", 30000).empty()) << daemon->output();
  // Wait until the gate setpoint has left the nominal, so the restore is needed.
  ASSERT_TRUE(daemon->WaitUntil(
      [&] { return std::abs(ReadSetpoint(canal.master) - nominal) > 1e-3; }, 10000, 50))
      << daemon->output();
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  const std::size_t term = daemon->output().find("SIGTERM: stopping");
  ASSERT_NE(term, std::string::npos) << daemon->output();
  EXPECT_NE(daemon->output().find(" restored", term), std::string::npos) << daemon->output();
}

// Wait until the daemon is exciting and the PRBS has moved the gate away from the nominal.
bool WaitExciting(ChildProcess& daemon, Master& master, double nominal) {
  if (daemon.WaitForLine("experiment exciting", 30000).empty()) return false;
  return daemon.WaitUntil([&] { return std::abs(ReadSetpoint(master) - nominal) > 1e-3; }, 10000,
                          50);
}

// The LCM log the daemon wrote (file://...?mode=w), read after it stopped.
struct LcmRecord {
  std::vector<canalid::sample_t> samples;
  std::map<std::string, std::map<std::string, int64_t>> last_health;  // component -> counters
  int configs = 0;
};

LcmRecord ReadLcmLog(const fs::path& path) {
  LcmRecord record;
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) return record;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == "CANALID_ASCE2_CONFIG") {
      ++record.configs;
    } else if (e->channel == "CANALID_ASCE2_SAMPLE_asce2") {
      canalid::sample_t m;
      if (m.decode(e->data, 0, e->datalen) == e->datalen) record.samples.push_back(m);
    } else if (e->channel == "CANALID_ASCE2_HEALTH") {
      canalid::health_t m;
      if (m.decode(e->data, 0, e->datalen) != e->datalen) continue;
      auto& counters = record.last_health[m.component];
      for (int i = 0; i < m.num_counters; ++i)
        counters[m.counter_names[static_cast<std::size_t>(i)]] =
            m.counter_values[static_cast<std::size_t>(i)];
    }
  }
  return record;
}

// Samples whose pool2_level the daemon flagged out of range.
int CountOutOfRangeLevels(const LcmRecord& record) {
  int n = 0;
  for (const canalid::sample_t& m : record.samples) {
    for (int c = 0; c < m.num_channels; ++c) {
      n += m.channel_names[static_cast<std::size_t>(c)] == "pool2_level" &&
           m.quality[static_cast<std::size_t>(c)] == canalid::sample_t::QUALITY_OUT_OF_RANGE;
    }
  }
  return n;
}

// Whole plant seconds of canalsim's clock (input registers 4-5).
std::uint32_t PlantSeconds(Master& master) {
  const std::vector<std::uint16_t> r = master.Inputs(4, 2);
  return (static_cast<std::uint32_t>(r[0]) << 16) | r[1];
}

// The daemon stalls (SIGSTOP) for 3 wall s mid-PRBS: the next sample is 3 s after the last, far
// beyond the 0.5 s bound, so the experiment aborts on the gap, restores the nominal and identifies
// nothing (without the check the gap went into the record as one sample and a model was saved).
TEST(DaemonCanalsim, AStalledDaemonAbortsTheExperimentOnTheSampleGap) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  const std::string config = WriteConfig(dir / "canalidd.toml", BaseKeys(canal.serve.port(), dir),
                                         ExplicitExperiment(0.05, 7));
  auto daemon = StartDaemon(dir, config);
  ASSERT_TRUE(WaitExciting(*daemon, canal.master, nominal)) << daemon->output();
  ASSERT_EQ(kill(daemon->pid(), SIGSTOP), 0);
  const std::uint32_t stopped_at = PlantSeconds(canal.master);
  // 3 wall s = 1800 plant s; bounded by canalsim's clock, which runs on without the daemon.
  daemon->WaitUntil([&] { return PlantSeconds(canal.master) >= stopped_at + 1800; }, 20000, 50);
  const std::uint32_t resumed_at = PlantSeconds(canal.master);
  ASSERT_EQ(kill(daemon->pid(), SIGCONT), 0);
  ASSERT_GE(resumed_at, stopped_at + 1800);
  const std::string abort = daemon->WaitForLine("experiment aborted (sample gap of ", 20000);
  ASSERT_FALSE(abort.empty()) << daemon->output();
  EXPECT_NE(abort.find("(bound 0.5 s)"), std::string::npos) << abort;
  ASSERT_FALSE(daemon->WaitForLine(" restored", 20000, Position(*daemon, abort)).empty())
      << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_EQ(daemon->output().find("reach pool2: identified"), std::string::npos)
      << daemon->output();
  EXPECT_FALSE(fs::exists(dir / "state" / "pool2.id.json"));
}

// 4. The PLC drops the daemon's connection mid-experiment: the experiment aborts on the lost link,
// the daemon reconnects, restores the nominal and keeps running.
TEST(DaemonCanalsim, PlcDisconnectAbortsReconnectsAndRestores) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  const std::string config = WriteConfig(dir / "canalidd.toml", BaseKeys(canal.serve.port(), dir),
                                         ExplicitExperiment(0.05, 7));
  auto daemon = StartDaemon(dir, config);
  ASSERT_TRUE(WaitExciting(*daemon, canal.master, nominal)) << daemon->output();
  canal.master.Write(kDropFault, 2);  // the next two requests get their connection closed
  // The poll (link lost) or the PRBS write (write failed) meets the dropped connection first.
  const std::string lost = daemon->WaitForLine("experiment aborted (", 20000);
  EXPECT_TRUE(lost.find("PLC link lost") != std::string::npos ||
              lost.find("setpoint write failed") != std::string::npos)
      << lost;
  ASSERT_FALSE(lost.empty()) << daemon->output();
  // The restore needs a working link again: its confirmation proves the reconnection.
  ASSERT_FALSE(daemon->WaitForLine(" restored", 20000, Position(*daemon, lost)).empty())
      << daemon->output();
  EXPECT_TRUE(daemon->Running());
  // The test's own master may have been one of the dropped: reconnect before reading.
  canal.master.Reconnect();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  const LcmRecord record = ReadLcmLog(dir / "run.lcmlog");
  const auto& plc = record.last_health.at("plc.asce2");
  EXPECT_GE(plc.at("reconnects"), 1);
  EXPECT_GE(plc.at("read_errors.disconnected") + plc.at("connect_failures"), 1);
}

// The values of channel `name` in the valid samples of `samples`, in order.
std::vector<double> ChannelValues(const std::vector<canalid::sample_t>& samples,
                                  const std::string& name) {
  std::vector<double> values;
  for (const canalid::sample_t& m : samples) {
    for (int c = 0; c < m.num_channels; ++c) {
      if (m.channel_names[static_cast<std::size_t>(c)] == name &&
          m.quality[static_cast<std::size_t>(c)] == canalid::sample_t::QUALITY_VALID)
        values.push_back(m.values[static_cast<std::size_t>(c)]);
    }
  }
  return values;
}

// mode = "step" live on pool 2, the process models reading the gate's measured position
// (actuator_position): the setpoint goes up by the amplitude for hold_s, back to nominal for as
// long (the daemon's own SAMPLE messages of the setpoint register), the foptd fit of the response
// is logged, and the nominal is where it ends.
TEST(DaemonCanalsim, StepExperimentStepsHoldsReturnsAndFitsAFoptd) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  auto keys = BaseKeys(canal.serve.port(), dir);
  keys.emplace_back("online_models",
                    "[\"id\", \"frac-foptd\"]\nactuator_position = \"gate1_position\"");
  keys.emplace_back("batch_models", "[\"id\", \"idz\", \"foptd\"]");
  // 60 samples up, 60 back (Ts = 60 plant s): 12 wall s.
  const std::string step =
      "[[experiment]]\nname = \"pool2_step\"\nreach = \"pool2\"\nmode = \"step\"\n"
      "amplitude = 0.05\nhold_s = 3600.0\nsettle_s = 0.0\nstart = \"on_start\"\n"
      "max_sample_gap_periods = 5.0\n\n[commands]\nenabled = false\n";
  const std::string config = WriteConfig(dir / "canalidd.toml", keys, step);
  auto daemon = StartDaemon(dir, config);
  const std::string line = daemon->WaitForLine("reach pool2: identified foptd ", 60000);
  ASSERT_FALSE(line.empty()) << daemon->output();
  const nlohmann::json foptd = JsonAfter(line, "identified foptd ");
  ASSERT_TRUE(foptd.is_object()) << line;
  EXPECT_GT(foptd.at("gain").get<double>(), 0.0) << line;
  EXPECT_GT(foptd.at("delay_s").get<double>(), 0.0) << line;
  EXPECT_LE(foptd.at("delay_s").get<double>(), 1400.0) << line;
  EXPECT_NEAR(foptd.at("input_offset").get<double>(), nominal, 2e-3) << line;  // the position
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);

  const std::vector<double> setpoints =
      ChannelValues(ReadLcmLog(dir / "run.lcmlog").samples, "gate1_setpoint");
  int up = 0, above = 0;
  for (const double v : setpoints) {
    up += std::abs(v - (nominal + 0.05)) < 1e-4;
    above += v > nominal + 0.05 + 1e-4;
  }
  // The hold is 60 samples. The register shows a write one poll later as a rule, and up to a few
  // polls later when the machine is loaded (57 seen with both cores busy), so the bounds allow
  // five polls of lag; a hold of another length (30, 120) still fails them.
  EXPECT_GE(up, 55);
  EXPECT_LE(up, 61);
  EXPECT_EQ(above, 0);
  ASSERT_FALSE(setpoints.empty());
  EXPECT_NEAR(setpoints.back(), nominal, 1e-4);
}

// 4a. SIGKILL mid-PRBS and an immediate restart, as systemd's Restart=on-failure does (RestartSec=5
// is far inside the PLC's 300 s watchdog; here the watchdog is 36000 plant s = 60 wall s, so the
// gate stays at the PRBS level the killed daemon left, as on site): the restarted daemon's first
// write is the nominal persisted before the excitation, it says so, it does not take the PRBS level
// as the nominal, and its own experiment is centred on the true nominal.
TEST(DaemonCanalsim, KilledMidPrbsRestartRestoresThePersistedNominalFirst) {
  const fs::path dir = TestDir();
  const fs::path plc = Asce2PlcWithWatchdog(dir, "36000.0");
  ASSERT_FALSE(plc.empty()) << "config/sim/plc/asce2.toml has no heartbeat_timeout_s = 300.0";
  ServeProcess serve({"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc", plc.string(),
                      "--time-scale", "600"},
                     dir / "canalsim.err");
  Master master(serve.port(), 2.0);
  const double nominal = ReadSetpoint(master);
  constexpr double kAmplitude = 0.05;
  const std::string config = WriteConfig(dir / "canalidd.toml", BaseKeys(serve.port(), dir),
                                         ExplicitExperiment(kAmplitude, 7));  // 25 s of PRBS
  const fs::path guard_path = dir / "state" / "pool2.experiment.json";

  auto first = StartDaemon(dir, config);
  ASSERT_TRUE(WaitExciting(*first, master, nominal)) << first->output();
  // Kill once the gate has reached a full PRBS level (the first step may be cut by the rate
  // limit; bounded: 200 reads, 50 ms apart).
  ASSERT_TRUE(first->WaitUntil(
      [&] { return std::abs(std::abs(ReadSetpoint(master) - nominal) - kAmplitude) < 1e-4; }, 10000,
      50))
      << first->output();
  EXPECT_NE(first->output().find("experiment guard persisted"), std::string::npos)
      << first->output();
  EXPECT_EQ(first->Stop(SIGKILL), 128 + SIGKILL);
  const double prbs_level = ReadSetpoint(master);
  ASSERT_GT(std::abs(prbs_level - nominal), 1e-3) << "not killed mid-PRBS";
  const nlohmann::json guard = nlohmann::json::parse(ReadText(guard_path), nullptr, false);
  ASSERT_TRUE(guard.is_object()) << ReadText(guard_path);
  EXPECT_EQ(guard.value("actuator", ""), "gate1_setpoint");
  EXPECT_DOUBLE_EQ(guard.value("nominal_setpoint", 0.0), nominal);

  // At once, with the same configuration and state directory.
  auto second = StartDaemon(dir, config, "canalidd-2.log", "run-2.lcmlog");
  const std::string marker = "interrupted experiment on reach pool2: restoring nominal ";
  const std::string interrupted = second->WaitForLine(marker, 20000);
  ASSERT_FALSE(interrupted.empty()) << second->output();
  EXPECT_NEAR(std::stod(interrupted.substr(interrupted.find(marker) + marker.size())), nominal,
              1e-6)
      << interrupted;
  EXPECT_NE(interrupted.find(" persisted at "), std::string::npos) << interrupted;
  const std::string restored =
      second->WaitForLine(" restored", 20000, Position(*second, interrupted));
  ASSERT_FALSE(restored.empty()) << second->output();
  ASSERT_FALSE(
      second->WaitForLine("experiment exciting", 20000, Position(*second, restored)).empty())
      << second->output();
  // The new experiment moves the gate to both PRBS levels around the true nominal, never further
  // (around the PRBS level it would reach nominal +- 2 x amplitude; bounded: 200 reads, 50 ms
  // apart).
  bool below = false, above = false, off_centre = false;
  second->WaitUntil(
      [&] {
        const double value = ReadSetpoint(master);
        below = below || std::abs(value - (nominal - kAmplitude)) < 1e-4;
        above = above || std::abs(value - (nominal + kAmplitude)) < 1e-4;
        off_centre = off_centre || std::abs(value - nominal) > kAmplitude + 1e-4;
        return below && above;
      },
      10000, 50);
  EXPECT_TRUE(below && above) << second->output();
  EXPECT_FALSE(off_centre);
  EXPECT_EQ(second->Stop(SIGTERM), 0) << second->output();
  EXPECT_NEAR(ReadSetpoint(master), nominal, 1e-4);
  EXPECT_EQ(second->output().find("(read from the PLC)"), std::string::npos) << second->output();
  // The clean stop confirmed the nominal: no guard is left for the next start.
  EXPECT_FALSE(fs::exists(guard_path)) << ReadText(guard_path);

  // The gate as the restarted daemon polled it: the PRBS level, then the restarted daemon's first
  // writes, straight to the true nominal (in steps when the rate limit cuts them, never past it);
  // only then the new PRBS around it.
  const LcmRecord record = ReadLcmLog(dir / "run-2.lcmlog");
  const std::vector<double> gate = ChannelValues(record.samples, "gate1_setpoint");
  ASSERT_FALSE(gate.empty());
  EXPECT_NEAR(gate.front(), prbs_level, 1e-6);
  std::size_t k = 1;
  for (; k < gate.size() && std::abs(gate[k] - nominal) > 1e-6; ++k) {
    EXPECT_LE(std::abs(gate[k] - nominal), std::abs(gate[k - 1] - nominal) + 1e-9)
        << "sample " << k << ": " << gate[k] << " moves away from the nominal " << nominal;
  }
  ASSERT_LT(k, gate.size()) << "the nominal never came back";
  for (; k < gate.size(); ++k)
    EXPECT_LE(std::abs(gate[k] - nominal), kAmplitude + 1e-4) << k << ": " << gate[k];
  // The experiment state message says so; `canalid replay` reads the restarted run without a
  // divergence (a second of samples gives no online estimate yet: "no model" is its exit 1).
  bool published = false;
  lcm::LogFile log((dir / "run-2.lcmlog").string(), "r");
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "CANALID_ASCE2_EXPERIMENT_pool2") continue;
    canalid::experiment_state_t m;
    if (m.decode(e->data, 0, e->datalen) != e->datalen) continue;
    if (m.reason.rfind("interrupted experiment: restoring nominal", 0) == 0) {
      published = true;
      EXPECT_EQ(static_cast<int>(m.state), +canalid::experiment_state_t::STATE_ABORTED);
      EXPECT_NEAR(m.setpoint, nominal, 1e-9);
    }
  }
  EXPECT_TRUE(published);
  const ProgramRun replay =
      RunProgram(CanalidProgram() + " replay " + (dir / "run-2.lcmlog").string(), dir);
  EXPECT_TRUE(replay.exit_code == 0 || replay.err.find("no model: no reach had samples for an "
                                                       "estimate") != std::string::npos)
      << replay.err;
  EXPECT_EQ(replay.err.find("diverges"), std::string::npos) << replay.err;
  EXPECT_EQ(replay.err.find("cannot"), std::string::npos) << replay.err;
}

// The experiment guard cannot be persisted (a directory sits where the store writes the guard's
// temporary file: open() refuses it, also to root): the experiment aborts before any excitation
// write with the reason, the gate never leaves its nominal, and the daemon carries on polling and
// stops cleanly.
TEST(DaemonCanalsim, GuardNotPersistedAbortsBeforeAnyExcitationWrite) {
  const fs::path dir = TestDir();
  fs::create_directories(dir / "state" / ".pool2.experiment.json.tmp" / "in-the-way");
  ServeProcess serve({"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc",
                      SourcePath("config/sim/plc/asce2.toml"), "--time-scale", "600"},
                     dir / "canalsim.err");
  Master master(serve.port(), 2.0);
  const double nominal = ReadSetpoint(master);
  const std::string config =
      WriteConfig(dir / "canalidd.toml", BaseKeys(serve.port(), dir), ExplicitExperiment(0.05, 7));
  auto daemon = StartDaemon(dir, config);
  const std::string refused =
      daemon->WaitForLine("reach pool2: experiment guard not persisted", 30000);
  ASSERT_FALSE(refused.empty()) << daemon->output();
  EXPECT_NE(refused.find("no excitation"), std::string::npos) << refused;
  const std::string aborted = daemon->WaitForLine(
      "reach pool2: experiment aborted (experiment guard not persisted)", 20000);
  ASSERT_FALSE(aborted.empty()) << daemon->output();
  // The gate, read by the test's own master for 2 wall s after the abort (bounded: 40 reads, 50 ms
  // apart), stays at its nominal.
  bool moved = false;
  daemon->WaitUntil(
      [&] {
        moved = moved || std::abs(ReadSetpoint(master) - nominal) > 1e-6;
        return moved;
      },
      2000, 50);
  EXPECT_FALSE(moved) << "the gate left its nominal " << nominal;
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_EQ(daemon->output().find("experiment guard persisted"), std::string::npos)
      << daemon->output();
  EXPECT_EQ(daemon->output().find("experiment exciting"), std::string::npos) << daemon->output();
  // Every gate value the daemon polled and published is the nominal; the daemon polled on after
  // the abort (the abort came at the experiment's first sample, 0.1 wall s after the start, and
  // the test watched for 2 s more: about 20 polls at 10 Hz, 20 exactly on a loaded machine, so
  // half of that is asked for).
  const LcmRecord record = ReadLcmLog(dir / "run.lcmlog");
  const std::vector<double> gate = ChannelValues(record.samples, "gate1_setpoint");
  ASSERT_GE(gate.size(), 10U);
  for (std::size_t k = 0; k < gate.size(); ++k) {
    ASSERT_NEAR(gate[k], nominal, 1e-6) << "sample " << k;
  }
  EXPECT_NEAR(ReadSetpoint(master), nominal, 1e-6);
}

// canalsim serve on `port` (0: a free one) as a plain child, so it can be restarted on the same
// port; returns the port from its ready line (0 when it did not come).
int StartServe(std::unique_ptr<ChildProcess>& serve, const fs::path& dir, int port,
               const std::string& log_name) {
  std::vector<std::string> argv = {CanalsimProgram(), "serve", "--listen",
                                   "127.0.0.1:" + std::to_string(port)};
  for (const std::string& a : Canal::Args({})) argv.push_back(a);
  serve = std::make_unique<ChildProcess>(argv, std::vector<std::string>{}, dir / log_name);
  const std::string ready = serve->WaitForLine("listening on 127.0.0.1:", 60000);
  if (ready.empty()) return 0;
  return std::stoi(ready.substr(ready.find("127.0.0.1:") + 10));
}

// 4b. The PLC restarts (canalsim killed and started again on the same port) mid-experiment: the
// experiment aborts on the lost link, the daemon reconnects to the new PLC and restores the gate.
TEST(DaemonCanalsim, PlcRestartAbortsReconnectsAndRestores) {
  const fs::path dir = TestDir();
  std::unique_ptr<ChildProcess> serve;
  const int port = StartServe(serve, dir, 0, "canalsim-1.log");
  ASSERT_GT(port, 0) << serve->output();
  double nominal = 0.0;
  {
    Master master(port, 2.0);
    nominal = ReadSetpoint(master);
  }
  const std::string config =
      WriteConfig(dir / "canalidd.toml", BaseKeys(port, dir), ExplicitExperiment(0.05, 7));
  auto daemon = StartDaemon(dir, config);
  ASSERT_FALSE(daemon->WaitForLine("experiment exciting", 30000).empty()) << daemon->output();
  EXPECT_EQ(serve->Stop(SIGKILL), 128 + SIGKILL);
  // Whichever sees the dead PLC first aborts: the next poll (link lost) or the next PRBS write.
  const std::string lost = daemon->WaitForLine("experiment aborted (", 20000);
  ASSERT_FALSE(lost.empty()) << daemon->output();
  EXPECT_TRUE(lost.find("PLC link lost") != std::string::npos ||
              lost.find("setpoint write failed") != std::string::npos)
      << lost;
  ASSERT_EQ(StartServe(serve, dir, port, "canalsim-2.log"), port) << serve->output();
  // The backoff is at most 5 s (backoff_max_s); the restore confirms the new connection.
  ASSERT_FALSE(daemon->WaitForLine(" restored", 30000, Position(*daemon, lost)).empty())
      << daemon->output();
  EXPECT_TRUE(daemon->Running());
  Master master(port, 2.0);
  EXPECT_NEAR(ReadSetpoint(master), nominal, 1e-4);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  EXPECT_EQ(serve->Stop(SIGTERM), 0) << serve->output();
}

// 5. Exception replies and spiking levels are counted, not fatal: the experiment aborts on the
// invalid level run, polls come back once the faults are off, and the daemon keeps running.
TEST(DaemonCanalsim, ExceptionRepliesAndSpikesAreCountedNotFatal) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const double nominal = ReadSetpoint(canal.master);
  const std::string config = WriteConfig(dir / "canalidd.toml", BaseKeys(canal.serve.port(), dir),
                                         ExplicitExperiment(0.05, 7));
  auto daemon = StartDaemon(dir, config);
  ASSERT_TRUE(WaitExciting(*daemon, canal.master, nominal)) << daemon->output();
  canal.master.Write(kExceptionFault, 4);  // slave device failure on every read; writes still work
  const std::string aborted =
      daemon->WaitForLine("experiment aborted (level sensor invalid)", 20000);
  ASSERT_FALSE(aborted.empty()) << daemon->output();
  ASSERT_FALSE(daemon->WaitForLine(" restored", 20000, Position(*daemon, aborted)).empty())
      << daemon->output();
  canal.master.Write(kExceptionFault, 0);
  // Spikes of +1 m on pool record 1 (pool 2) every 7th plant step: 3.1 m, above valid_max 2.5.
  // The daemon polls every 6 plant steps (0.1 wall s x 600 / 10 s): with a period of 2 polls in
  // phase with the odd steps never met a spike; 7 is coprime with 6, so whatever their phase the
  // polls meet one at least every 7 polls.
  canal.master.Write(kSpikeAmplitude, 1000);
  canal.master.Write(kSpikePeriod, 7);
  canal.master.Write(kSpikeRecords, 1 << 1);
  // Spikes on until the daemon's LCM log holds an out-of-range level, rechecked every 0.2 s for at
  // most 20 s (a fixed window failed when other builds loaded both cores).
  EXPECT_TRUE(daemon->WaitUntil(
      [&] { return CountOutOfRangeLevels(ReadLcmLog(dir / "run.lcmlog")) > 0; }, 20000, 200))
      << "no out-of-range level in the log within 20 s";
  canal.master.Write(kSpikeRecords, 0);
  EXPECT_TRUE(daemon->Running()) << daemon->output();
  EXPECT_NEAR(ReadSetpoint(canal.master), nominal, 1e-4);
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();

  const LcmRecord record = ReadLcmLog(dir / "run.lcmlog");
  const auto& plc = record.last_health.at("plc.asce2");
  EXPECT_GT(plc.at("read_errors.exception"), 0);
  // After the last exception reply, the polls answer again (status ok) ...
  std::size_t last_exception = 0;
  for (std::size_t i = 0; i < record.samples.size(); ++i) {
    if (record.samples[i].status == canalid::sample_t::STATUS_EXCEPTION) last_exception = i + 1;
  }
  ASSERT_GT(last_exception, 0U);
  int ok_after = 0;
  int out_of_range = 0;
  for (std::size_t i = last_exception; i < record.samples.size(); ++i) {
    const canalid::sample_t& m = record.samples[i];
    if (m.status == canalid::sample_t::STATUS_OK) ++ok_after;
    for (int c = 0; c < m.num_channels; ++c) {
      if (m.channel_names[static_cast<std::size_t>(c)] == "pool2_level" &&
          m.quality[static_cast<std::size_t>(c)] == canalid::sample_t::QUALITY_OUT_OF_RANGE) {
        ++out_of_range;
      }
    }
  }
  EXPECT_GT(ok_after, 10);
  // ... and the spikes were flagged as out of range instead of passed on as levels.
  EXPECT_GT(out_of_range, 0);
}

// Starts canalidd in a private network namespace with a multicast route on its loopback, so
// canalid-command (entered into the same namespace) and the daemon share a udpm bus.
constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7667?ttl=0";
// A channel the tests play onto the udpm bus to make lcm-logger take in what came before it.
constexpr const char* kProbeChannel = "CANALID_TEST_PROBE";
const std::string kUdpmEnv = std::string("LCM_DEFAULT_URL=") + kUdpmUrl;

int SendCommand(const fs::path& dir, pid_t daemon_pid, const fs::path& key,
                const std::vector<std::string>& args) {
  std::vector<std::string> argv = InPrivateNetworkOf(daemon_pid);
  const std::vector<std::string> sender = {
      CommandProgram(), "--key", key.string(), "--channel", "CANALID_ASCE2_COMMAND",
      "--reach",        "pool2", "--sender",   "test"};
  argv.insert(argv.end(), sender.begin(), sender.end());
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess command(argv, {kUdpmEnv}, dir / "command.log");
  return command.WaitExit(10000);
}

void WriteKey(const fs::path& path, const std::string& hex) {
  std::ofstream(path) << hex << "\n";
  ::chmod(path.c_str(), 0600);
}

// canalsim (ASCE canal 2 at 600 x) in a private network namespace, canalidd with commands enabled
// on `key` and lcm-logger recording the udpm bus (bus.lcmlog), all three in that namespace.
struct CommandRig {
  fs::path key;
  fs::path bus_log;
  std::unique_ptr<ChildProcess> canal;
  std::unique_ptr<ChildProcess> daemon;
  std::unique_ptr<ChildProcess> logger;
  int probes = 0;  // publish-config commands sent until the logger recorded a configuration

  pid_t network() const { return canal->pid(); }
};

// Starts the rig with `experiments` (TOML [[experiment]] tables) and the key 00 11 .. ff twice;
// fails the test (and returns with what it started) when a part is not ready in time.
void StartCommandRig(const fs::path& dir, const std::string& experiments, CommandRig& rig) {
  ASSERT_TRUE(fs::exists("/usr/bin/lcm-logger")) << "lcm-logger (Debian liblcm-bin) missing";
  const std::string network_problem = PrivateNetworkProblem(dir);
  ASSERT_TRUE(network_problem.empty()) << network_problem;
  rig.key = dir / "command.key";
  WriteKey(rig.key, "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff");
  const std::string commands =
      "[commands]\nenabled = true\nkey_file = \"" + rig.key.string() + "\"\n";
  // canalsim makes the namespace (its loopback is the only one the daemon can reach there); the
  // daemon and every canalid-command enter it.
  std::vector<std::string> canal_argv = InNewPrivateNetwork();
  for (const std::string& a :
       {CanalsimProgram(), std::string("serve"), std::string("--listen"),
        std::string("127.0.0.1:0"), std::string("--canal"),
        SourcePath("config/sim/asce-canal2.toml"), std::string("--plc"),
        SourcePath("config/sim/plc/asce2.toml"), std::string("--time-scale"), std::string("600")}) {
    canal_argv.push_back(a);
  }
  rig.canal =
      std::make_unique<ChildProcess>(canal_argv, std::vector<std::string>{}, dir / "canalsim.log");
  const std::string ready = rig.canal->WaitForLine("listening on 127.0.0.1:", 60000);
  ASSERT_FALSE(ready.empty()) << rig.canal->output();
  const int port = std::stoi(ready.substr(ready.find("127.0.0.1:") + 10));
  const std::string config =
      WriteConfig(dir / "canalidd.toml", BaseKeys(port, dir), experiments + "\n" + commands);
  std::vector<std::string> daemon_argv = InPrivateNetworkOf(rig.network());
  for (const std::string& a : {DaemonProgram(), std::string("--config"), config}) {
    daemon_argv.push_back(a);
  }
  rig.daemon = std::make_unique<ChildProcess>(daemon_argv, std::vector<std::string>{kUdpmEnv},
                                              dir / "canalidd.log");
  ASSERT_FALSE(rig.daemon->WaitForLine("commands enabled", 20000).empty()) << rig.daemon->output();
  ASSERT_FALSE(rig.daemon->WaitForLine("answers: ready", 20000).empty()) << rig.daemon->output();

  // lcm-logger in the namespace records the bus. It is ready once a configuration the daemon
  // republishes on a genuine publish-config command shows up in its file (bounded: 50 tries,
  // 100 ms apart).
  rig.bus_log = dir / "bus.lcmlog";
  std::vector<std::string> logger_argv = InPrivateNetworkOf(rig.network());
  for (const std::string& a :
       {std::string("/usr/bin/lcm-logger"), std::string("-f"), std::string("--flush-interval=10"),
        std::string("--lcm-url=") + kUdpmUrl, rig.bus_log.string()}) {
    logger_argv.push_back(a);
  }
  rig.logger = std::make_unique<ChildProcess>(logger_argv, std::vector<std::string>{},
                                              dir / "lcm-logger.log");
  ASSERT_TRUE(rig.logger->WaitUntil(
      [&] {
        if (ReadLcmLog(rig.bus_log).configs > 0) return true;
        EXPECT_EQ(SendCommand(dir, rig.network(), rig.key, {"publish-config"}), 0);
        ++rig.probes;
        return false;
      },
      5000, 100))
      << rig.logger->output();
}

// 6. Commands: a genuine start starts the experiment; a forged, a stale and a replayed command
// are rejected and change nothing.
TEST(DaemonCanalsim, CommandsStartOnlyWhenGenuine) {
  const fs::path dir = TestDir();
  CommandRig rig;
  StartCommandRig(dir, ExplicitExperiment(0.05, 7, "manual", ""), rig);
  ASSERT_FALSE(::testing::Test::HasFailure());
  const fs::path key = rig.key;
  const fs::path wrong_key = dir / "wrong.key";
  WriteKey(wrong_key, "ffeeddccbbaa99887766554433221100ffeeddccbbaa99887766554433221100");
  ChildProcess& canal = *rig.canal;
  ChildProcess& daemon = *rig.daemon;
  ChildProcess& logger = *rig.logger;
  const fs::path& bus_log = rig.bus_log;
  const int probes = rig.probes;

  const auto now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  // Explicit counters above those of the probes (which default to the time of sending).
  auto counter = [&](int n) { return std::to_string(now_us + n); };
  EXPECT_EQ(SendCommand(dir, canal.pid(), wrong_key, {"start", "--counter", counter(10)}), 0);
  ASSERT_FALSE(daemon.WaitForLine("command rejected (bad_mac)", 10000).empty()) << daemon.output();
  // One hour old: far outside max_clock_skew_s.
  EXPECT_EQ(SendCommand(dir, canal.pid(), key,
                        {"start", "--counter", counter(20), "--utime-us",
                         std::to_string(now_us - 3600LL * 1000000LL)}),
            0);
  ASSERT_FALSE(daemon.WaitForLine("command rejected (stale)", 10000).empty()) << daemon.output();
  EXPECT_EQ(daemon.output().find("experiment settling"), std::string::npos) << daemon.output();
  EXPECT_EQ(daemon.output().find("experiment exciting"), std::string::npos) << daemon.output();

  EXPECT_EQ(SendCommand(dir, canal.pid(), key, {"start", "--counter", counter(30)}), 0);
  const std::string started = daemon.WaitForLine("experiment exciting", 10000);
  ASSERT_FALSE(started.empty()) << daemon.output();
  // The same counter again (a replayed abort) must not stop the experiment.
  EXPECT_EQ(SendCommand(dir, canal.pid(), key, {"stop", "--counter", counter(30)}), 0);
  ASSERT_FALSE(daemon.WaitForLine("command rejected (replayed)", 10000).empty()) << daemon.output();
  EXPECT_EQ(daemon.output().find("experiment aborted"), std::string::npos) << daemon.output();
  // A genuine stop with a new counter does.
  EXPECT_EQ(SendCommand(dir, canal.pid(), key, {"stop", "--counter", counter(40)}), 0);
  EXPECT_FALSE(daemon.WaitForLine("experiment aborted (stopped by operator)", 10000).empty())
      << daemon.output();
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();
  // The daemon's last health message crosses the bus to the logger after the daemon has exited,
  // and lcm-logger writes an event out when the next one comes: send commands nobody answers now
  // (bounded: 50 x 100 ms) until the health message is in the file, then stop the logger.
  logger.WaitUntil(
      [&] {
        if (ReadLcmLog(bus_log).last_health.count("commands") > 0) return true;
        EXPECT_EQ(SendCommand(dir, canal.pid(), key, {"publish-config"}), 0);
        return false;
      },
      5000, 100);
  EXPECT_EQ(logger.Stop(SIGINT), 0) << logger.output();
  EXPECT_EQ(canal.Stop(SIGTERM), 0) << canal.output();
  // The health message the daemon publishes as it stops counts every verdict once.
  const LcmRecord record = ReadLcmLog(bus_log);
  ASSERT_EQ(record.last_health.count("commands"), 1U);
  const auto& verdicts = record.last_health.at("commands");
  EXPECT_EQ(verdicts.at("verdicts.bad_mac"), 1);
  EXPECT_EQ(verdicts.at("verdicts.stale"), 1);
  EXPECT_EQ(verdicts.at("verdicts.replayed"), 1);
  EXPECT_EQ(verdicts.at("verdicts.accepted"), 2 + probes);  // start, stop and the probes
}

// An operator starts the reach's second experiment by name over the command channel: the daemon
// runs that one (not the first), identifies its record, and `canalid replay` of the bus log that
// lcm-logger recorded (the configuration republished by publish-config, then the samples and the
// experiment states naming the experiment) starts the same experiment at the same sample and
// gives the same batch models.
TEST(DaemonCanalsim, AnOperatorStartedExperimentReplaysFromTheBusLog) {
  const fs::path dir = TestDir();
  // The first experiment (pool2_short, 127 bits of 2 samples) is not the one started; the second
  // is shorter: 63 bits of 2 samples (12.6 s at 600 x). Its gap bound is 2 s (20 polls), not the
  // demo's 0.5 s: this test is about the replay, and on two cores shared with other suites a poll
  // came 0.5 s late once and aborted it (the gap rule has its own test, AStalledDaemon...).
  const std::string quick =
      "[[experiment]]\nname = \"pool2_quick\"\nreach = \"pool2\"\nmode = \"explicit\"\n"
      "amplitude = 0.05\nclock_period_s = 120.0\norder = 6\nseed = 3\nsettle_s = 0.0\n"
      "start = \"manual\"\nmax_invalid_samples = 3\nmax_sample_gap_periods = 20.0\n";
  CommandRig rig;
  StartCommandRig(dir, ExplicitExperiment(0.05, 7, "manual", "") + "\n" + quick, rig);
  ASSERT_FALSE(::testing::Test::HasFailure());
  ChildProcess& daemon = *rig.daemon;
  EXPECT_EQ(SendCommand(dir, rig.network(), rig.key, {"start", "--argument", "pool2_quick"}), 0);
  // The id model's line: "identified {json}" (the other kinds name themselves).
  const std::string identified = daemon.WaitForLine("reach pool2: identified {", 60000);
  ASSERT_FALSE(identified.empty()) << daemon.output();
  EXPECT_NE(daemon.output().find("starting the experiment pool2_quick"), std::string::npos)
      << daemon.output();
  const nlohmann::json live = JsonAfter(identified, "identified ");
  ASSERT_TRUE(live.is_object()) << identified;
  // The daemon keeps polling, so the batch model's message is followed by samples and written
  // out by the logger (bounded: 100 x 100 ms).
  const std::string model_channel = "CANALID_ASCE2_MODEL_pool2";
  auto batch_models = [&] {
    int n = 0;
    for (const canalid::model_snapshot_t& m : ModelMessagesIn(rig.bus_log, model_channel)) {
      n += m.estimator == "batch";
    }
    return n;
  };
  EXPECT_TRUE(rig.logger->WaitUntil([&] { return batch_models() > 0; }, 10000, 100));
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();
  EXPECT_EQ(rig.logger->Stop(SIGINT), 0) << rig.logger->output();
  EXPECT_EQ(rig.canal->Stop(SIGTERM), 0) << rig.canal->output();

  // Replay checks its batch models against the ones published live (and says so); the final
  // id model it prints is the one the daemon logged.
  std::string err;
  std::map<std::string, nlohmann::json> replayed = ReplayedModelsOf(rig.bus_log, dir, "", "", &err);
  EXPECT_NE(err.find("batch id model vs the last one published live: largest relative "
                     "difference 0\n"),
            std::string::npos)
      << err;
  ASSERT_EQ(replayed.count("id"), 1U) << err;
  EXPECT_EQ(JsonNumbersDiffer(live, replayed["id"], 1e-12), "");
  EXPECT_EQ(live.at("delay_s"), replayed["id"].at("delay_s"));
}

// Every message on the bus log by channel, and the sample_t, health_t and experiment_t ones
// decoded.
struct BusRecord {
  std::map<std::string, int> count;                                // channel -> messages
  std::map<std::string, std::vector<canalid::sample_t>> samples;   // channel -> samples
  std::map<std::string, std::set<std::string>> health_components;  // channel -> components
};

BusRecord ReadBus(const fs::path& path) {
  BusRecord record;
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) return record;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++record.count[e->channel];
    if (e->channel.find("_SAMPLE_") != std::string::npos) {
      canalid::sample_t m;
      if (m.decode(e->data, 0, e->datalen) == e->datalen) record.samples[e->channel].push_back(m);
    } else if (e->channel.size() > 7 && e->channel.ends_with("_HEALTH")) {
      canalid::health_t m;
      if (m.decode(e->data, 0, e->datalen) == e->datalen)
        record.health_components[e->channel].insert(m.component);
    }
  }
  return record;
}

// The mean of channel `name` over the valid values of `samples`; NaN without any.
double MeanValue(const std::vector<canalid::sample_t>& samples, const std::string& name) {
  double sum = 0.0;
  int n = 0;
  for (const canalid::sample_t& m : samples) {
    for (int c = 0; c < m.num_channels; ++c) {
      if (m.channel_names[static_cast<std::size_t>(c)] == name &&
          m.quality[static_cast<std::size_t>(c)] == canalid::sample_t::QUALITY_VALID) {
        sum += m.values[static_cast<std::size_t>(c)];
        ++n;
      }
    }
  }
  return n > 0 ? sum / n : std::nan("");
}

// 6b. Scale-out: two canalsim PLCs and two daemons with their own channel prefixes on one udpm
// bus; one lcm-logger sees both daemons' samples, experiments and health on their own channels.
// The second canal runs 1 m3/s less into pool 1; the offtakes are fixed flows, so its pool 2
// inflow is the first's minus 1 m3/s: a sample on the wrong prefix would show it.
TEST(DaemonCanalsim, TwoDaemonsShareOneBusOnTheirOwnPrefixes) {
  ASSERT_TRUE(fs::exists("/usr/bin/lcm-logger")) << "lcm-logger (Debian liblcm-bin) missing";
  const fs::path dir = TestDir();
  const std::string network_problem = PrivateNetworkProblem(dir);
  ASSERT_TRUE(network_problem.empty()) << network_problem;

  // The second canal: config/sim/asce-canal2.toml with 10 instead of 11 m3/s at the head (more
  // does not pass the gates at their level setpoints).
  std::string canal_b_text = ReadText(SourcePath("config/sim/asce-canal2.toml"));
  const std::string head_flow = "flow_m3s = 11.0";
  ASSERT_NE(canal_b_text.find(head_flow), std::string::npos);
  canal_b_text.replace(canal_b_text.find(head_flow), head_flow.size(), "flow_m3s = 10.0");
  const fs::path canal_b_path = dir / "canal-b.toml";
  std::ofstream(canal_b_path) << canal_b_text;

  auto serve_args = [&](const std::string& canal) {
    return std::vector<std::string>{
        CanalsimProgram(), "serve", "--listen", "127.0.0.1:0",
        "--canal",         canal,   "--plc",    SourcePath("config/sim/plc/asce2.toml"),
        "--time-scale",    "600"};
  };
  std::vector<std::string> argv_a = InNewPrivateNetwork();
  for (const std::string& a : serve_args(SourcePath("config/sim/asce-canal2.toml")))
    argv_a.push_back(a);
  ChildProcess canal_a(argv_a, {}, dir / "canalsim-a.log");
  const std::string ready_a = canal_a.WaitForLine("listening on 127.0.0.1:", 60000);
  ASSERT_FALSE(ready_a.empty()) << canal_a.output();
  const int port_a = std::stoi(ready_a.substr(ready_a.find("127.0.0.1:") + 10));
  const std::vector<std::string> enter = InPrivateNetworkOf(canal_a.pid());
  auto in_namespace = [&](const std::vector<std::string>& argv) {
    std::vector<std::string> all = enter;
    all.insert(all.end(), argv.begin(), argv.end());
    return all;
  };
  ChildProcess canal_b(in_namespace(serve_args(canal_b_path.string())), {}, dir / "canalsim-b.log");
  const std::string ready_b = canal_b.WaitForLine("listening on 127.0.0.1:", 60000);
  ASSERT_FALSE(ready_b.empty()) << canal_b.output();
  const int port_b = std::stoi(ready_b.substr(ready_b.find("127.0.0.1:") + 10));

  const fs::path bus_log = dir / "bus.lcmlog";
  ChildProcess logger(in_namespace({"/usr/bin/lcm-logger", "-f", "--flush-interval=10",
                                    std::string("--lcm-url=") + kUdpmUrl, bus_log.string()}),
                      {}, dir / "lcm-logger.log");

  // Daemon B: its own state folder, prefix and PLC name ("asce2b" wherever "asce2" is quoted).
  fs::create_directories(dir / "state-b");
  const std::string config_a =
      WriteConfig(dir / "canalidd-a.toml", BaseKeys(port_a, dir), ExplicitExperiment(0.02, 4));
  auto keys_b = BaseKeys(port_b, dir);
  keys_b[1].second = "\"" + (dir / "state-b").string() + "\"";
  keys_b.emplace_back("channel_prefix", "\"CANALID_B_\"");
  const fs::path config_b = dir / "canalidd-b.toml";
  std::string text_b = ReadText(WriteConfig(config_b, keys_b, ExplicitExperiment(0.02, 4)));
  for (std::size_t at = text_b.find("\"asce2\""); at != std::string::npos;
       at = text_b.find("\"asce2\"", at))
    text_b.replace(at, 7, "\"asce2b\"");
  std::ofstream(config_b) << text_b;

  ChildProcess daemon_a(in_namespace({DaemonProgram(), "--config", config_a}), {kUdpmEnv},
                        dir / "canalidd-a.log");
  ChildProcess daemon_b(in_namespace({DaemonProgram(), "--config", config_b.string()}), {kUdpmEnv},
                        dir / "canalidd-b.log");
  // Order 4, two samples per bit: 30 samples (3 s) of excitation; wait until both have started.
  ASSERT_FALSE(daemon_a.WaitForLine("experiment exciting", 30000).empty()) << daemon_a.output();
  ASSERT_FALSE(daemon_b.WaitForLine("experiment exciting", 30000).empty()) << daemon_b.output();
  // Until the logger's file holds 15 samples of each (bounded: 30 s), so the counts checked
  // below do not depend on how fast this machine is.
  auto samples_of = [](const BusRecord& b, const char* channel) {
    const auto it = b.samples.find(channel);
    return it == b.samples.end() ? std::size_t{0} : it->second.size();
  };
  EXPECT_TRUE(daemon_a.WaitUntil(
      [&] {
        const BusRecord so_far = ReadBus(bus_log);
        return samples_of(so_far, "CANALID_ASCE2_SAMPLE_asce2") >= 15 &&
               samples_of(so_far, "CANALID_B_SAMPLE_asce2b") >= 15;
      },
      30000, 100));
  EXPECT_EQ(daemon_a.Stop(SIGTERM), 0) << daemon_a.output();
  EXPECT_EQ(daemon_b.Stop(SIGTERM), 0) << daemon_b.output();
  // Each daemon publishes its health as it stops. lcm-logger drops what it has not read yet when
  // it is interrupted, and writes its file out only as further messages arrive: so a probe event
  // is played onto the bus (lcm-logplayer, in the namespace) until both health messages are in
  // the file, and only then is the logger stopped (bounded: 50 probes, 100 ms apart).
  const fs::path probe_log = dir / "probe.lcmlog";
  {
    lcm::LogFile probe(probe_log.string(), "w");
    lcm::LogEvent event{};
    const std::string channel = kProbeChannel;
    std::array<uint8_t, 1> byte{0};
    event.channel = channel;
    event.datalen = 1;
    event.data = byte.data();
    ASSERT_EQ(probe.writeEvent(&event), 0);
  }
  const bool recorded = logger.WaitUntil(
      [&] {
        const BusRecord so_far = ReadBus(bus_log);
        if (so_far.health_components.count("CANALID_ASCE2_HEALTH") == 1 &&
            so_far.health_components.count("CANALID_B_HEALTH") == 1) {
          return true;
        }
        ChildProcess play(in_namespace({"/usr/bin/lcm-logplayer",
                                        std::string("--lcm-url=") + kUdpmUrl, probe_log.string()}),
                          {}, dir / "lcm-logplayer.log");
        EXPECT_EQ(play.WaitExit(10000), 0) << play.output();
        return false;
      },
      10000, 100);
  EXPECT_TRUE(recorded) << "the daemons' last health messages never reached the logger's file";
  EXPECT_EQ(logger.Stop(SIGINT), 0) << logger.output();
  EXPECT_EQ(canal_b.Stop(SIGTERM), 0) << canal_b.output();
  EXPECT_EQ(canal_a.Stop(SIGTERM), 0) << canal_a.output();

  const BusRecord bus = ReadBus(bus_log);
  // Only the two daemons' channels, each under its own prefix and PLC name (and the udpm
  // provider's own self test).
  for (const auto& [channel, n] : bus.count) {
    if (channel == "LCM_SELF_TEST" || channel == kProbeChannel) continue;
    EXPECT_TRUE(channel.starts_with("CANALID_ASCE2_") || channel.starts_with("CANALID_B_"))
        << channel;
    EXPECT_NE(channel, "CANALID_ASCE2_SAMPLE_asce2b");
    EXPECT_NE(channel, "CANALID_B_SAMPLE_asce2");
  }
  const auto& samples_a = bus.samples.at("CANALID_ASCE2_SAMPLE_asce2");
  const auto& samples_b = bus.samples.at("CANALID_B_SAMPLE_asce2b");
  // At 10 polls per second over at least 3 s each, half of them as a margin for a loaded machine.
  EXPECT_GE(samples_a.size(), 15U);
  EXPECT_GE(samples_b.size(), 15U);
  for (const auto& m : samples_a) EXPECT_EQ(m.source, "asce2");
  for (const auto& m : samples_b) EXPECT_EQ(m.source, "asce2b");
  // Pool 2 inflow: 10 m3/s in the first canal (domain/README.md, high regime); the PRBS on gate 1
  // moves it by a few percent, hence 0.5 m3/s; the second canal's is 1 m3/s less (fixed offtakes).
  const double inflow_a = MeanValue(samples_a, "pool2_inflow");
  const double inflow_b = MeanValue(samples_b, "pool2_inflow");
  EXPECT_NEAR(inflow_a, 10.0, 0.5);
  EXPECT_NEAR(inflow_a - inflow_b, 1.0, 0.3);
  for (const std::string prefix : {"CANALID_ASCE2_", "CANALID_B_"}) {
    EXPECT_GE(bus.count.count(prefix + "EXPERIMENT_pool2"), 1U) << prefix;
    ASSERT_EQ(bus.health_components.count(prefix + "HEALTH"), 1U) << prefix;
  }
  EXPECT_EQ(bus.health_components.at("CANALID_ASCE2_HEALTH").count("plc.asce2"), 1U);
  EXPECT_EQ(bus.health_components.at("CANALID_ASCE2_HEALTH").count("plc.asce2b"), 0U);
  EXPECT_EQ(bus.health_components.at("CANALID_B_HEALTH").count("plc.asce2b"), 1U);
  EXPECT_EQ(bus.health_components.at("CANALID_B_HEALTH").count("plc.asce2"), 0U);
}

// 7. A broken configuration: exit 78 and one file:line:column line per problem.
// SIGHUP: an invalid configuration is refused and the daemon carries on; a valid one is taken
// (here a new LCM channel prefix), without restarting the process or truncating its LCM log.
TEST(DaemonCanalsim, SighupReloadsAValidConfigurationOnly) {
  const fs::path dir = TestDir();
  Canal canal(dir);
  const fs::path config_path = dir / "canalidd.toml";
  const std::string config = WriteConfig(config_path, BaseKeys(canal.serve.port(), dir),
                                         ExplicitExperiment(0.05, 4, "manual"));
  auto daemon = StartDaemon(dir, config);
  ASSERT_FALSE(daemon->WaitForLine("answers: ready", 30000).empty()) << daemon->output();

  WriteConfig(config_path, {{"port", "70000"}}, ExplicitExperiment(0.05, 4, "manual"));
  kill(daemon->pid(), SIGHUP);
  ASSERT_FALSE(daemon->WaitForLine("not valid; carrying on", 20000).empty()) << daemon->output();
  EXPECT_NE(daemon->output().find("plc[0].port"), std::string::npos) << daemon->output();
  EXPECT_TRUE(daemon->Running());

  std::vector<std::pair<std::string, std::string>> keys = BaseKeys(canal.serve.port(), dir);
  keys.emplace_back("channel_prefix", "\"CANALID_RELOADED_\"");
  WriteConfig(config_path, keys, ExplicitExperiment(0.05, 4, "manual"));
  const std::size_t before = daemon->output().size();
  kill(daemon->pid(), SIGHUP);
  ASSERT_FALSE(daemon->WaitForLine("LCM prefix CANALID_RELOADED_", 20000, before).empty())
      << daemon->output();
  EXPECT_NE(daemon->output().find("reloading the configuration", before), std::string::npos);
  EXPECT_FALSE(daemon->WaitForLine("answers: ready", 20000, before).empty()) << daemon->output();
  EXPECT_TRUE(daemon->Running());
  EXPECT_EQ(daemon->Stop(SIGTERM), 0) << daemon->output();
  // The log kept what the first configuration published, and holds the reloaded channels too.
  const std::string log = ReadText(dir / "run.lcmlog");
  EXPECT_NE(log.find("CANALID_ASCE2_SAMPLE_asce2"), std::string::npos);
  EXPECT_NE(log.find("CANALID_RELOADED_SAMPLE_asce2"), std::string::npos);
}

TEST(DaemonCanalsim, CheckConfigReportsProblemsWithPositions) {
  const fs::path dir = TestDir();
  const fs::path config = dir / "broken.toml";
  WriteConfig(config, {{"port", "70000"}, {"poll_period_s", "-1.0"}});
  ChildProcess check({DaemonProgram(), "--config", config.string(), "--check-config"}, {},
                     dir / "check.log");
  EXPECT_EQ(check.WaitExit(20000), 78) << check.output();
  // Each problem names the file, the line and column of the key, then the key path.
  const std::string prefix = config.string() + ":";
  EXPECT_NE(check.output().find(prefix), std::string::npos) << check.output();
  EXPECT_NE(check.output().find("plc[0].port"), std::string::npos) << check.output();
  EXPECT_NE(check.output().find("plc[0].poll_period_s"), std::string::npos) << check.output();
  std::istringstream lines(check.output());
  std::string line;
  int positioned = 0;
  while (std::getline(lines, line)) {
    if (line.rfind(prefix, 0) != 0) continue;
    // file:LINE:COLUMN: ...
    const std::string rest = line.substr(prefix.size());
    std::size_t a = 0;
    std::size_t b = 0;
    std::stoi(rest, &a);
    std::stoi(rest.substr(a + 1), &b);
    EXPECT_EQ(rest[a], ':');
    EXPECT_EQ(rest[a + 1 + b], ':');
    ++positioned;
  }
  EXPECT_GE(positioned, 2) << check.output();
}

}  // namespace
}  // namespace canalid::testing
