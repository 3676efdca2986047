// `canalid identify --online` run as a program: the held-out Saint-Venant check of issue 4, online
// ARX against the batch fit, the --trace file against the printed snapshot, and bad options.
// The records are canalsim's Preissmann solutions for ASCE canal 2 pool 2 at 10 m3/s (IDZ,
// Litrico & Fromion 2004: delay 682 s, backwater area 34113 m2), tests/data/sim.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_program.h"

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
  }
}

// The online bank is an open-loop estimator.  On the fixed-gate record the outflow follows the
// level (closed loop), which biases the open-loop fit: the batch command switches to the
// three-step method there (33.3k m2), its open-loop cross-check gives 43.1k m2 (+26 %).  What the
// online run must do is equal that open-loop fit exactly (forgetting 1, P0 = 1e10: 1e-6 relative,
// the tolerance); the held-out 20 % check on this record needs an online closed-loop
// variant, which is not there yet.
TEST(OnlineCli, IdOnFixedGateRecordEqualsTheBatchOpenLoopFit) {
  const std::string csv = Record("asce2-pool2-prbs-fixed-gate");
  const auto online = Identify("fixed-gate", "--model id --online --input " + csv);
  const auto batch = Identify("fixed-gate-batch", "--model id --closed-loop off --input " + csv);
  EXPECT_EQ(online["nk"], batch["nk"]);
  EXPECT_LT(Rel(online["b"].get<double>(), batch["b"].get<double>()), 1e-6);
  EXPECT_LT(Rel(online["p21_s_per_m2"].get<double>(), batch["p21_s_per_m2"].get<double>()), 1e-6);
  EXPECT_GE(online["delay_s"].get<double>(), 0.5 * kIdzDelay);
  EXPECT_LE(online["delay_s"].get<double>(), 1.2 * kIdzDelay);
}

TEST(OnlineCli, ArxWithForgettingOneEqualsBatchArx) {
  const std::string args = "--model arx --u q_in,q_out --y level --na 2 --nb 2 --nk 11,1 --input " +
                           Record("asce2-pool2-prbs-fixed-gate");
  const auto batch = Identify("arx-batch", args);
  const auto online = Identify("arx-online", args + " --online --forgetting 1");
  EXPECT_EQ(online["estimator"], "online-ud_directional");
  // P0 = 1e10 against an information matrix of O(1e2..1e5): the prior is far below 1e-6.
  for (int j = 0; j < 2; ++j) {
    EXPECT_LT(Rel(online["a"][j].get<double>(), batch["a"][j].get<double>()), 1e-6) << j;
  }
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      EXPECT_LT(Rel(online["b_coeffs"][i][j].get<double>(), batch["b_coeffs"][i][j].get<double>()),
                1e-6)
          << i << " " << j;
    }
  }
  // With lambda = 1 the innovation variance is the batch SSR / (N - d), so the standard
  // deviations sqrt(sigma2 P_ii) are the batch ones too.
  for (int j = 0; j < 6; ++j) {
    EXPECT_LT(
        Rel(online["parameter_std"][j].get<double>(), batch["parameter_std"][j].get<double>()),
        1e-6)
        << j;
  }
  EXPECT_LT(Rel(online["loss"].get<double>(), batch["loss"].get<double>()), 1e-6);
  EXPECT_EQ(online["equations"], batch["equations"]);
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
  ExpectBadInput("method", "--model arx --u q_in --y level --online --method fast" + csv,
                 "--method fast: unknown (allowed: ud_directional");
  ExpectBadInput("kind", "--model foptd --u q_in --y level --online" + csv,
                 "--model foptd has no online estimator (online: id, arx)");
}

}  // namespace
}  // namespace canalid::testing
