// canalidd beside the lab flume (seed 2): config/canalidd-lab-flume.toml against canalsim serve
// (config/sim/lab-flume.toml behind config/sim/plc/lab-flume.toml, 5 plant s per wall s), once
// with its PRBS and once with its step experiment. At the end of each experiment the online
// frac-foptd bank (at the configured delay) must agree with the batch frac-foptd fit of the same
// record after the step (the tolerances: alpha 0.08, K 10 %, T 20 %; see the tests for
// what holds), and `canalid replay` of the run's LCM log must give the same batch model.  The
// truths: the batch fits (FitFractionalFoptd, an output-error fit by simulation, a different
// estimator from the online bank's equation error), the flume paper's ranges, and the PLC's
// setpoint register read by a separate Modbus master.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/sim/serve_process.h"
#include "tests/support/daemon_experiment_run.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kGateSetpoint = 300;  // holding float, record 0 (the undershot gate), "abcd"

fs::path TestDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "daemon_lab_flume" / info->name();
  fs::remove_all(dir);
  fs::create_directories(dir / "state");
  return dir;
}

// Runs `experiment` of the flume's daemon to its end against canalsim, and checks the gate is
// back at its nominal once the daemon stopped.
DaemonExperimentRun RunFlumeExperiment(const std::string& experiment) {
  const fs::path dir = TestDir();
  ServeProcess serve({"--canal", SourcePath("config/sim/lab-flume.toml"), "--plc",
                      SourcePath("config/sim/plc/lab-flume.toml"), "--time-scale", "5"},
                     dir / "canalsim.err");
  Master master(serve.port(), 2.0);
  const double nominal = master.HoldingFloatAbcd(kGateSetpoint);
  const std::string config =
      RewriteDaemonConfig(SourcePath("config/canalidd-lab-flume.toml"),
                          {{"port", std::to_string(serve.port())},
                           {"state_directory", "\"" + (dir / "state").string() + "\""},
                           // 20 polls (1.2 wall s) instead of the file's 5 (0.3 s): this machine is
                           // shared while the tests run, and a late poll is no fault to test here.
                           {"max_sample_gap_periods", "20.0"}},
                          experiment);
  // The PRBS: 6 + 180 plant s = 37 wall s; the step 6 + 120 plant s = 25 wall s.  Bounded at 3x
  // for a loaded machine.
  DaemonExperimentRun run = RunDaemonExperiment(dir, config, "pool", "CANALID_FLUME_", 120000);
  EXPECT_NEAR(master.HoldingFloatAbcd(kGateSetpoint), nominal, 1e-6);
  EXPECT_NE(run.output.find("reach pool: starting the experiment " + experiment + "\n"),
            std::string::npos)
      << run.output;
  // Every state message names the experiment that ran (the shipped file lists the PRBS first).
  EXPECT_EQ(run.experiments, std::set<std::string>{experiment});
  return run;
}

// The batch fits are of the flume (the flume paper's ranges over its 1080 experiments: K
// 0.086-0.775, T 1.1-48.94 s, tau 2.25-5.7 s; the fractional model's delay too), and the replay
// of the log gives the live batch model exactly.
void ExpectBatchOfTheFlume(const DaemonExperimentRun& run) {
  ASSERT_EQ(run.batch.count("frac-foptd"), 1U) << run.output;
  ASSERT_EQ(run.batch.count("foptd"), 1U) << run.output;
  const nlohmann::json& f = run.batch.at("foptd");
  EXPECT_GT(f.at("gain").get<double>(), 0.086) << f;
  EXPECT_LT(f.at("gain").get<double>(), 0.775) << f;
  EXPECT_GT(f.at("time_constant_s").get<double>(), 1.1) << f;
  EXPECT_LT(f.at("time_constant_s").get<double>(), 48.94) << f;
  EXPECT_GT(f.at("delay_s").get<double>(), 2.25) << f;
  EXPECT_LT(f.at("delay_s").get<double>(), 5.7) << f;
  const nlohmann::json& g = run.batch.at("frac-foptd");
  EXPECT_GT(g.at("delay_s").get<double>(), 2.25) << g;
  EXPECT_LT(g.at("delay_s").get<double>(), 5.7) << g;
  ASSERT_EQ(run.batch.count("soptd"), 1U) << run.output;
  const nlohmann::json& s = run.batch.at("soptd");
  EXPECT_GT(s.at("gain").get<double>(), 0.086) << s;
  EXPECT_LT(s.at("gain").get<double>(), 0.775) << s;
  EXPECT_GT(s.at("delay_s").get<double>(), 0.0) << s;
  EXPECT_LT(s.at("delay_s").get<double>(), 5.7) << s;
  // The replay fits the same three models to the same record, to the last bit.
  for (const char* kind : {"foptd", "soptd"}) {
    EXPECT_NE(run.replay_err.find(std::string("batch ") + kind +
                                  " model vs the last one published live: largest relative "
                                  "difference 0\n"),
              std::string::npos)
        << kind << "\n"
        << run.replay_err;
  }
  ASSERT_EQ(run.replayed.count("frac-foptd"), 1U) << run.replay_err;
  for (const char* key : {"gain", "time_constant_s", "alpha", "delay_s"}) {
    EXPECT_EQ(run.replayed.at("frac-foptd").at(key).get<double>(), g.at(key).get<double>()) << key;
  }
  // Replay's own check of the batch model it fitted against the live one.
  EXPECT_NE(run.replay_err.find("batch frac-foptd model vs the last one published live: largest "
                                "relative difference 0\n"),
            std::string::npos)
      << run.replay_err;
}

// The online frac-foptd at the end of the experiment against the batch fit of the same record:
// alpha within 0.08, K within 10 %, T within t_fraction of the batch's, the configured delay.
void ExpectOnlineNearTheBatch(const DaemonExperimentRun& run, double t_fraction) {
  ASSERT_EQ(run.online.count("frac-foptd"), 1U);
  const auto& online = run.online.at("frac-foptd");
  const nlohmann::json& b = run.batch.at("frac-foptd");
  const double k = b.at("gain").get<double>();
  const double t = b.at("time_constant_s").get<double>();
  EXPECT_NEAR(online.at("alpha"), b.at("alpha").get<double>(), 0.08) << b;
  EXPECT_NEAR(online.at("gain"), k, 0.10 * k) << b;
  EXPECT_NEAR(online.at("time_constant_s"), t, t_fraction * t) << b;
  EXPECT_EQ(online.at("delay_s"), 5.1);  // configured: 17 samples of 0.3 s
}

TEST(DaemonLabFlume, PrbsIdentifiesTheFlumeAndReplaysIt) {
  const DaemonExperimentRun run = RunFlumeExperiment("pool_prbs");
  ExpectBatchOfTheFlume(run);
  // The tolerances.  Measured (2026-11-29, the output-error grid bank): batch alpha
  // 0.460, K 0.918, T 4.02 s; online alpha 0.45, K 0.914, T 3.88 s.
  ExpectOnlineNearTheBatch(run, 0.20);
}

TEST(DaemonLabFlume, StepOnlineFractionalModelMatchesTheBatchFit) {
  const DaemonExperimentRun run = RunFlumeExperiment("pool_step");
  ExpectBatchOfTheFlume(run);
  // The tolerances.  Measured (2026-11-29): batch alpha 0.51, K 0.744, T 2.72 s; online
  // alpha 0.55, K 0.705, T 2.90 s.  The recursive bank this one replaced (a parallel-model
  // pseudo-linear regression per alpha) ended 24 % off in T here: its T drifted in the last hold
  // and no forgetting, P0, dead zone or re-simulation brought it within 20 % in one pass.  The
  // grid bank's loss is the exact output-error loss of each (alpha, T) candidate, so it has no
  // such drift.
  ExpectOnlineNearTheBatch(run, 0.20);
}

}  // namespace
}  // namespace canalid::testing
