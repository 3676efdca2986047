// `canalid identify --online` run as a program: the held-out Saint-Venant check of issue 4, online
// ARX against the batch fit, the --trace file against the printed snapshot, and bad options.
// The records are canalsim's Preissmann solutions for ASCE canal 2 pool 2 at 10 m3/s (IDZ,
// Litrico & Fromion 2004: delay 682 s, backwater area 34113 m2), tests/data/sim.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

constexpr double kIdzDelay = 682.0;
constexpr double kIdzArea = 34113.0;

std::string Record(const std::string& name) {
  return std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/" + name + ".csv";
}

nlohmann::json Identify(const std::string& test, const std::string& args) {
  const auto dir = TestDirectory("online-" + test);
  const ProgramRun run = RunProgram(CanalidProgram() + " identify " + args, dir);
  EXPECT_EQ(run.exit_code, 0) << args << "\n" << run.err;
  return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json::object();
}

double Rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

void ExpectHeldOutTolerances(const nlohmann::json& model) {
  // Issue 4: online, area within 20 % of IDZ's and delay within 0.5-1.2 x IDZ's.
  EXPECT_NEAR(model["area_m2"].get<double>(), kIdzArea, 0.20 * kIdzArea) << model.dump();
  EXPECT_GE(model["delay_s"].get<double>(), 0.5 * kIdzDelay) << model.dump();
  EXPECT_LE(model["delay_s"].get<double>(), 1.2 * kIdzDelay) << model.dump();
}

TEST(OnlineCli, IdOnCleanAndNoisyRecordsMeetsTheHeldOutTolerances) {
  for (const char* name : {"asce2-pool2-prbs", "asce2-pool2-prbs-noisy"}) {
    const auto model =
        Identify(name, "--model id --online --max-delay-s 3600 --input " + Record(name));
    ExpectHeldOutTolerances(model);
    EXPECT_EQ(model["model"], "id");
    EXPECT_EQ(model["estimator"], "online-ud_directional");
    EXPECT_GT(model["health"]["updates"].get<int>(), 500);
    EXPECT_FALSE(model["health"]["wound_up"].get<bool>());
    // A designed experiment swings the level by centimetres through the flow term (measured
    // 20 mm), far above the 0.1 mm under which the snapshot is flagged: no health flag.
    EXPECT_GT(model["flow_level_rms_m"].get<double>(), 0.01) << model.dump();
    EXPECT_EQ(model["flags"], 0) << model.dump();
  }
}

// --closed-loop off: the least-squares bank equals the batch open-loop fit exactly (forgetting 1,
// P0 = 1e10: 1e-6 relative, the tolerance), delay included: both pick 720 s (nk = 12; the
// batch scan's loss is 1.3 x its minimum at 11 and 2.8 x at 13, no near-tie).  On the fixed-gate
// record the outflow follows the level, which biases the area (43.7k m2, +28 %).  Before p21 >= 0
// was the bank's (core::OnlineIntegratorDelayOptions::wave_front_non_negative) rather than the
// RLS box's, the clamped candidates 8..13 never recovered and the bank picked 840 s here.
TEST(OnlineCli, IdOnFixedGateRecordEqualsTheBatchOpenLoopFit) {
  const std::string csv = Record("asce2-pool2-prbs-fixed-gate");
  const auto online =
      Identify("fixed-gate", "--model id --online --closed-loop off --input " + csv);
  const auto batch = Identify("fixed-gate-batch", "--model id --closed-loop off --input " + csv);
  EXPECT_EQ(online["nk"], batch["nk"]);
  EXPECT_FALSE(online["closed_loop"].get<bool>());
  EXPECT_LT(Rel(online["b"].get<double>(), batch["b"].get<double>()), 1e-6);
  EXPECT_LT(Rel(online["p21_s_per_m2"].get<double>(), batch["p21_s_per_m2"].get<double>()), 1e-6);
  EXPECT_EQ(online.value("initial_covariance", 0.0), 1e10);  // the id kind's default P0
  EXPECT_GE(online["delay_s"].get<double>(), 0.5 * kIdzDelay);
  EXPECT_LE(online["delay_s"].get<double>(), 1.2 * kIdzDelay);
}

// The online idz kind fits the batch IDZ fit's zero-order-hold equation (p21 of the continuous
// model, Q(k) - q_in(k - nk) in the regression): on the open-loop record, with the same prior and
// delays, it equals the batch fit (measured: b 3e-11, p21 3e-10 relative).  With the id
// regression's Q(k) its p21 would be the batch's less b = Ts/A, 9.5 % off.
TEST(OnlineCli, IdzOnOpenLoopRecordEqualsTheBatchFit) {
  const std::string csv = Record("asce2-pool2-prbs");
  const std::string args = "--model idz --max-delay-s 1800 --p22 0.0133 --input " + csv;
  const auto online = Identify("idz-open", args + " --online");
  const auto batch = Identify("idz-open-batch", args);
  EXPECT_EQ(online["delay_s"], batch["delay_s"]);
  EXPECT_LT(Rel(online["b"].get<double>(), batch["b"].get<double>()), 1e-6);
  EXPECT_LT(Rel(online["p21_s_per_m2"].get<double>(), batch["p21_s_per_m2"].get<double>()), 1e-6);
  EXPECT_GT(batch["p21_s_per_m2"].get<double>(), 0.0);
}

// IDZ's outflow gain of this pool (Litrico & Fromion 2004, the same table as 34113 m2 and 682 s).
constexpr double kIdzP22 = 0.0216;

// Issue 4's held-out check on the fixed-gate record: --closed-loop auto (the default) detects the
// loop over the first 200 samples after the longest delay and reports the instrumental-variable
// bank; with IDZ's p22 the area is within 20 % of IDZ's (measured 32465 m2, -4.8 %) and the delay
// within 0.5-1.2 x (720 s).
TEST(OnlineCli, IdOnFixedGateRecordClosedLoopMeetsTheHeldOutTolerances) {
  const std::string csv = Record("asce2-pool2-prbs-fixed-gate");
  const auto model = Identify("fixed-gate-iv", "--model id --online --max-delay-s 3600 --p22 " +
                                                   std::to_string(kIdzP22) + " --input " + csv);
  ExpectHeldOutTolerances(model);
  EXPECT_TRUE(model["closed_loop"].get<bool>()) << model.dump();
  EXPECT_EQ(model["estimator"], "online-iv");
  EXPECT_NE(model["closed_loop_reason"].get<std::string>().find("outflow moves"),
            std::string::npos);
  EXPECT_FALSE(model["health"]["wound_up"].get<bool>());
}

// What the data cannot give: with a gate q_out ~ q0 + g y (g = 14.6 m2/s here) IDZ's -p22 q_out
// term acts as -p22 g y, so without p22 any fit of this regression estimates A (1 + p22 g) =
// 34113 x 1.32 = 44.9k m2.  The online IV gives that (44215 m2, -1.4 %): the bias is the model's,
// not the loop noise's, and --p22 (from the geometry) is the remedy.  Documented, not hidden.
TEST(OnlineCli, IdOnFixedGateRecordWithoutP22EstimatesAOnePlusP22G) {
  const std::string csv = Record("asce2-pool2-prbs-fixed-gate");
  const auto model =
      Identify("fixed-gate-iv-no-p22",
               "--model id --online --closed-loop iv --max-delay-s 3600 --input " + csv);
  const double g = 14.58;  // least squares of q_out on the cleaned level over the record
  EXPECT_LT(Rel(model["area_m2"].get<double>(), kIdzArea * (1.0 + kIdzP22 * g)), 0.05)
      << model.dump();
}

// The three-step method online (--closed-loop three-step) meets the held-out tolerances from the
// data alone, without p22: its step 3 fits the level on the flow simulated from the inflow
// through the estimated loop sensitivity F_hat, so the level-driven part of q_out (which carries
// IDZ's p22 g y into the IV and LS regressions) is not a regressor.  Measured 720 s, 34017 m2
// (-0.3 %); the delay comes from the IV bank (see core::OnlineIntegratorDelayOptions::closed_loop
// for the other choices, which fail here).  The open-loop records are unchanged under auto (above).
TEST(OnlineCli, IdOnFixedGateRecordThreeStepMeetsTheHeldOutTolerancesWithoutP22) {
  const std::string csv = Record("asce2-pool2-prbs-fixed-gate");
  const auto model =
      Identify("fixed-gate-three-step",
               "--model id --online --closed-loop three-step --max-delay-s 3600 --input " + csv);
  ExpectHeldOutTolerances(model);
  EXPECT_TRUE(model["closed_loop"].get<bool>());
  EXPECT_EQ(model["estimator"], "online-three-step");
  EXPECT_EQ(model["p22_s_per_m2"].get<double>(), 0.0);
  EXPECT_EQ(model["p21_s_per_m2"].get<double>(), 0.0);
}

// The open-loop records keep their result under auto (detected as open loop) and with p22 (the
// held outflow puts p22 q_out into the offset).
TEST(OnlineCli, IdOnOpenLoopRecordsIgnoresP22AndStaysOpenLoop) {
  for (const char* name : {"asce2-pool2-prbs", "asce2-pool2-prbs-noisy"}) {
    const std::string args = "--model id --online --max-delay-s 3600 --input " + Record(name);
    const auto plain = Identify(name, args);
    const auto with_p22 = Identify(std::string(name) + "-p22", args + " --p22 0.0216");
    ExpectHeldOutTolerances(with_p22);
    EXPECT_FALSE(with_p22["closed_loop"].get<bool>());
    EXPECT_LT(Rel(with_p22["b"].get<double>(), plain["b"].get<double>()), 1e-6);
  }
}

TEST(OnlineCli, ArxWithForgettingOneEqualsBatchArx) {
  const std::string args = "--model arx --u q_in,q_out --y level --na 2 --nb 2 --nk 11,1 --input " +
                           Record("asce2-pool2-prbs-fixed-gate");
  const auto batch = Identify("arx-batch", args);
  const auto online = Identify("arx-online", args + " --online --forgetting 1");
  EXPECT_EQ(online["estimator"], "online-ud_directional");
  // P0 = 1e10 against an information matrix of O(1e2..1e5): the prior is far below 1e-6.
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_LT(Rel(online["a"][j].get<double>(), batch["a"][j].get<double>()), 1e-6) << j;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_LT(Rel(online["b_coeffs"][i][j].get<double>(), batch["b_coeffs"][i][j].get<double>()),
                1e-6)
          << i << " " << j;
    }
  }
  // With lambda = 1 the innovation variance is the batch SSR / (N - d), so the standard
  // deviations sqrt(sigma2 P_ii) are the batch ones too.
  for (std::size_t j = 0; j < 6; ++j) {
    EXPECT_LT(
        Rel(online["parameter_std"][j].get<double>(), batch["parameter_std"][j].get<double>()),
        1e-6)
        << j;
  }
  EXPECT_LT(Rel(online["loss"].get<double>(), batch["loss"].get<double>()), 1e-6);
  EXPECT_EQ(online["equations"], batch["equations"]);
}

// --initial-covariance is the prior's weight: at 1e-8 (an information of 1e8 against the data's
// O(1e2..1e5)) the prior theta = 0 outweighs the record and the estimates stay far from the
// batch fit that the default P0 reproduces (above).
TEST(OnlineCli, InitialCovarianceSetsThePriorsWeight) {
  const std::string args = "--model arx --u q_in,q_out --y level --na 2 --nb 2 --nk 11,1 --input " +
                           Record("asce2-pool2-prbs-fixed-gate");
  const auto batch = Identify("arx-prior-batch", args);
  const auto tight = Identify("arx-prior-tight", args + " --online --initial-covariance 1e-8");
  EXPECT_EQ(tight.value("initial_covariance", 0.0), 1e-8);  // the JSON says which P0 it used
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_GT(Rel(tight["a"][j].get<double>(), batch["a"][j].get<double>()), 0.5) << j;
    EXPECT_LT(std::abs(tight["a"][j].get<double>()), 0.5 * std::abs(batch["a"][j].get<double>()))
        << j;
  }
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> parts;
  std::stringstream s(line);
  std::string part;
  while (std::getline(s, part, ',')) parts.push_back(part);
  return parts;
}

// The last row of --trace is the printed snapshot (17 significant digits round-trip exactly).
TEST(OnlineCli, TraceLastRowEqualsThePrintedSnapshot) {
  const auto dir = TestDirectory("online-trace");
  const std::string trace = (dir / "trace.csv").string();
  const auto model = Identify("trace-run",
                              "--model id --online --forgetting 0.999 --max-delay-s 3600 "
                              "--input " +
                                  Record("asce2-pool2-prbs") + " --trace " + trace);
  std::stringstream text(ReadFile(trace));
  std::string line, last;
  std::getline(text, line);
  const std::vector<std::string> header = Split(line);
  ASSERT_GE(header.size(), 6u);
  EXPECT_EQ(header[0], "time_s");
  EXPECT_EQ(header[1], "delay_s");
  EXPECT_EQ(header[2], "area_m2");
  EXPECT_EQ(header[3], "b");
  int rows = 0;
  while (std::getline(text, line)) {
    last = line;
    ++rows;
  }
  EXPECT_GT(rows, 500);
  const std::vector<std::string> values = Split(last);
  ASSERT_EQ(values.size(), header.size());
  EXPECT_DOUBLE_EQ(std::stod(values[0]), 840 * 60.0);  // the record's last sample
  for (std::size_t i = 1; i < header.size(); ++i) {
    const std::string& key = header[i];
    if (model.contains(key)) {
      EXPECT_DOUBLE_EQ(std::stod(values[i]), model[key].get<double>()) << key;
    } else if (model["health"].contains(key) && model["health"][key].is_number()) {
      EXPECT_DOUBLE_EQ(std::stod(values[i]), model["health"][key].get<double>()) << key;
    }
  }
  EXPECT_DOUBLE_EQ(std::stod(values[1]), model["delay_s"].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[2]), model["area_m2"].get<double>());
}

TEST(OnlineCli, ArxTraceLastRowEqualsThePrintedParameters) {
  const auto dir = TestDirectory("online-arx-trace");
  const std::string trace = (dir / "trace.csv").string();
  const auto model =
      Identify("arx-trace-run",
               "--model arx --u q_in --y level --nk 11 --online --method exponential "
               "--forgetting 0.995 --input " +
                   Record("asce2-pool2-prbs") + " --trace " + trace);
  EXPECT_EQ(model["estimator"], "online-exponential");
  std::stringstream text(ReadFile(trace));
  std::string line, last;
  std::getline(text, line);
  EXPECT_EQ(line.rfind("time_s,a1,a2,b1_1,b1_2,trace_p,prediction_error", 0), 0u) << line;
  while (std::getline(text, line)) last = line;
  const std::vector<std::string> values = Split(last);
  ASSERT_GE(values.size(), 7u);
  EXPECT_DOUBLE_EQ(std::stod(values[1]), model["a"][0].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[2]), model["a"][1].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[3]), model["b_coeffs"][0][0].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[4]), model["b_coeffs"][0][1].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[5]), model["health"]["trace_p"].get<double>());
  EXPECT_DOUBLE_EQ(std::stod(values[6]), model["prediction_error"].get<double>());
}

// An integer second-order plant (frac-ss with q = 1, alpha = 1: Delta x(k+1) = x(k+1) - x(k)),
// stepped here as x(k+1) = (I + A) x(k) + B u(k - 3) around a rest point (u 1.5, level 2.0):
// online frac-ss at the known delay finds its a and c and its rest point; the batch fit (its
// delay scanned) finds the same model.
TEST(OnlineCli, FracSsFindsACommensuratePlantAsTheBatchFitDoes) {
  const auto dir = TestDirectory("online-frac-ss-plant");
  constexpr double kA1 = 0.5, kA2 = 0.1, kC1 = 0.5;
  constexpr int kDelay = 3;
  std::mt19937 rng(3);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,gate,level\n";
  std::vector<double> du(400, 0.0);
  double x1 = 0.0, x2 = 0.0, held = 0.0;
  for (std::size_t k = 0; k < du.size(); ++k) {
    if (k > 0 && k % 5 == 1) held = (rng() & 1U) != 0U ? 0.1 : -0.1;
    du[k] = k == 0 ? 0.0 : held;
    csv << 2.0 * static_cast<double>(k) << "," << 1.5 + du[k] << "," << 2.0 + x1 + kC1 * x2 << "\n";
    const double u_delayed = k >= kDelay ? du[k - kDelay] : 0.0;
    const double next2 = x2 - kA2 * x1 - kA1 * x2 + kA2 * u_delayed;  // last row -[a2, a1], B = a2
    x1 += x2;
    x2 = next2;
  }
  WriteFile(dir / "plant.csv", csv.str());
  const std::string input = " --u gate --y level --q 1 --input " + (dir / "plant.csv").string();
  const nlohmann::json online =
      Identify("frac-ss", "--model frac-ss --online --nk " + std::to_string(kDelay) + input);
  ASSERT_FALSE(online.empty());
  EXPECT_EQ(online["model"], "frac-ss");
  EXPECT_EQ(online["delay_s"].get<double>(), 6.0);
  EXPECT_EQ(online["alpha"].get<double>(), 1.0);
  EXPECT_NEAR(online["a1"].get<double>(), kA1, 1e-6) << online.dump();
  EXPECT_NEAR(online["a2"].get<double>(), kA2, 1e-6) << online.dump();
  EXPECT_NEAR(online["c1"].get<double>(), kC1, 1e-5) << online.dump();
  EXPECT_EQ(online["input_operating_point"].get<double>(), 1.5);
  EXPECT_EQ(online["level_operating_point_m"].get<double>(), 2.0);
  const nlohmann::json batch =
      Identify("frac-ss-batch", "--model frac-ss --max-delay-s 20" + input);
  ASSERT_FALSE(batch.empty());
  EXPECT_EQ(batch["delay_samples"], kDelay);
  EXPECT_NEAR(-batch["A"][1][0].get<double>(), online["a2"].get<double>(), 1e-6);
  EXPECT_NEAR(-batch["A"][1][1].get<double>(), online["a1"].get<double>(), 1e-6);
  EXPECT_NEAR(batch["C"][1].get<double>(), online["c1"].get<double>(), 1e-5);

  // --alpha is frac-foptd's; frac-ss takes --q.
  const ProgramRun alpha =
      RunProgram(CanalidProgram() + " identify --model frac-ss --online --nk 3 " +
                     "--alpha 0.5 --u gate --y level --input " + (dir / "plant.csv").string(),
                 dir);
  EXPECT_EQ(alpha.exit_code, 2);
  EXPECT_NE(alpha.err.find("--alpha applies to --model frac-foptd"), std::string::npos)
      << alpha.err;
}

TEST(OnlineCli, EveryMethodRuns) {
  for (const char* method : {"ud_directional", "ud_exponential", "exponential", "directional",
                             "constant_trace", "stabilised", "kalman", "nlms"}) {
    const auto model = Identify(
        std::string("method-") + method,
        std::string("--model id --online --max-delay-s 1200 --forgetting 0.999 --method ") +
            method + " --input " + Record("asce2-pool2-prbs"));
    EXPECT_EQ(model["estimator"], std::string("online-") + method);
    EXPECT_TRUE(model["area_m2"].is_number()) << method;
  }
}

void ExpectBadInput(const std::string& test, const std::string& args, const std::string& message) {
  const auto dir = TestDirectory("online-bad-" + test);
  const ProgramRun run = RunProgram(CanalidProgram() + " identify " + args, dir);
  EXPECT_EQ(run.exit_code, 2) << args;
  EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
}

TEST(OnlineCli, BadOptionsExitTwoWithAClearMessage) {
  const std::string csv = " --input " + Record("asce2-pool2-prbs");
  ExpectBadInput("forgetting-zero", "--model id --online --forgetting 0" + csv,
                 "--forgetting 0: out of range (0 < L <= 1)");
  ExpectBadInput("forgetting-above-one", "--model id --online --forgetting 1.5" + csv,
                 "--forgetting 1.5: out of range (0 < L <= 1)");
  ExpectBadInput("p0-zero", "--model id --online --initial-covariance 0" + csv,
                 "--initial-covariance 0: out of range (0 < p0 <= 1e20)");
  ExpectBadInput("p0-huge", "--model id --online --initial-covariance 1e21" + csv,
                 "--initial-covariance 1e+21: out of range (0 < p0 <= 1e20)");
  // With --config the reach's settings are the daemon's; a flag beside them would do nothing.
  const std::string config =
      " --config " + std::string(CANALID_SOURCE_DIR) + "/config/canalidd-asce2.toml --reach pool2";
  ExpectBadInput("config-forgetting", "--model id --online --forgetting 0.99" + config + csv,
                 "--forgetting excludes --config");
  ExpectBadInput("config-p0", "--model id --online --initial-covariance 10" + config + csv,
                 "--initial-covariance excludes --config");
  ExpectBadInput("config-method", "--model id --online --method kalman" + config + csv,
                 "--method excludes --config");
  // So would the model's flags and columns: every one of them is refused beside --config.
  for (const std::string& flag :
       std::vector<std::string>{"--qin q_in",
                                "--qout q_out",
                                "--level level",
                                "--max-delay-s 600",
                                "--closed-loop off",
                                "--p22 0.01",
                                "--p22-std 0.001",
                                "--keep-outliers",
                                "--u q_in",
                                "--y level",
                                "--na 2",
                                "--nb 2",
                                "--nk 3",
                                "--detrend",
                                "--alpha 0.5",
                                "--q 2",
                                "--local arx",
                                "--schedule level",
                                "--bands 1,2",
                                "--bands-file " + Record("asce2-pool2-prbs"),
                                "--degree 1",
                                "--min-band-samples 50"}) {
    const std::string name = flag.substr(0, flag.find(' '));
    std::string args = "--model id --online ";
    args.append(flag).append(config).append(csv);
    ExpectBadInput("config" + name, args, name + " excludes --config");
  }
  ExpectBadInput("config-canal",
                 "--model id --online --canal " + std::string(CANALID_SOURCE_DIR) +
                     "/config/sim/asce-canal2.toml --pool 2" + config + csv,
                 "excludes --config");
  // The estimator's flags without --online (a batch fit) would do nothing.
  ExpectBadInput("forgetting-batch", "--model id --forgetting 0.99" + csv,
                 "--forgetting requires --online");
  ExpectBadInput("p0-batch", "--model id --initial-covariance 10" + csv,
                 "--initial-covariance requires --online");
  ExpectBadInput("method", "--model arx --u q_in --y level --online --method fast" + csv,
                 "--method fast: unknown (allowed: ud_directional");
  ExpectBadInput("kind", "--model foptd --u q_in --y level --online" + csv,
                 "--model foptd has no online estimator (online: id, arx, frac-foptd, lpv, idz, "
                 "frac-ss)");
}

}  // namespace
}  // namespace canalid::testing
