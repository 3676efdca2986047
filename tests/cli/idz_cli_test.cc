// `canalid identify --model idz` on the Saint-Venant records of ASCE canal 2 pool 2 (canalsim,
// tests/data/sim): the open-loop record, and the record whose pool ends at a free weir (the
// outflow follows the level; the file is named "fixed-gate"), with the prior from `--canal ...
// --pool 2` and without it. Reference: Litrico & Fromion (2004), 682 s and 34113 m2.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_program.h"
#include "tests/support/simulate_round_trip.h"

namespace canalid::testing {
namespace {

constexpr double kDelay = 682.0, kArea = 34113.0;

// A directory of each test's own (ctest runs the tests of this file side by side).
ProgramRun Identify(const std::string& record, const std::string& args) {
  const auto dir = TestDirectory(std::string("idz_cli_") +
                                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
  return RunProgram(CanalidProgram() + " identify --model idz --input " + CANALID_SOURCE_DIR +
                        "/tests/data/sim/" + record + ".csv " + args,
                    dir);
}

const std::string kCanal2 =
    std::string(" --canal ") + CANALID_SOURCE_DIR + "/config/sim/asce-canal2.toml --pool 2";

TEST(IdzCli, FreeWeirRecordWithTheGeometryPriorGetsTheArea) {
  const ProgramRun run = Identify("asce2-pool2-prbs-fixed-gate", "--max-delay-s 1800" + kCanal2);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["model"], "idz");
  EXPECT_EQ(json["p22_source"], "prior") << json["p22_reason"];
  EXPECT_TRUE(json["outflow_follows_level"].get<bool>());
  EXPECT_EQ(json["p22_prior"]["from"], "theory");
  EXPECT_EQ(json["p22_prior"]["pool"], "2");
  const double delay = json["delay_s"], area = json["area_m2"];
  EXPECT_GE(delay, 0.8 * kDelay);
  EXPECT_LE(delay, 1.2 * kDelay);
  EXPECT_NEAR(area / kArea, 1.0, 0.10) << area;  // measured 35736 m2, +4.8 %
  EXPECT_GT(json["area_std_m2"].get<double>(), 0.0);
  EXPECT_EQ(json["inputs"], nlohmann::json({"q_in", "q_out"}));
  EXPECT_EQ(json["output"], "level");
}

TEST(IdzCli, FreeWeirRecordWithoutPriorWarnsAndReadsTheClosedLoopArea) {
  const ProgramRun run = Identify("asce2-pool2-prbs-fixed-gate", "--max-delay-s 1800");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["p22_source"], "none");
  EXPECT_TRUE(json["p22_prior"].is_null());
  ASSERT_EQ(json["warnings"].size(), 1u);
  EXPECT_NE(json["warnings"][0].get<std::string>().find("A (1 + p22 g)"), std::string::npos);
  EXPECT_GT(json["area_m2"].get<double>() / kArea, 1.2);
}

TEST(IdzCli, OpenLoopRecordGetsTheAreaWithOrWithoutPrior) {
  for (const std::string& prior : {std::string(), kCanal2}) {
    const ProgramRun run = Identify("asce2-pool2-prbs", "--max-delay-s 1800" + prior);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto json = nlohmann::json::parse(run.out);
    EXPECT_FALSE(json["outflow_moves"].get<bool>());
    EXPECT_NEAR(json["area_m2"].get<double>() / kArea, 1.0, 0.10);  // measured +2.3 %
    EXPECT_EQ(json["p22_source"], prior.empty() ? "none" : "prior");
  }
}

// --online: the daemon's online idz kind (the id bank with the wave front and p22 held at the
// prior) on the free-weir record: the prior brings the area back from A (1 + p22 g).
TEST(IdzCli, OnlineIdzWithThePriorGetsTheArea) {
  const ProgramRun with =
      Identify("asce2-pool2-prbs-fixed-gate", "--online --max-delay-s 1800" + kCanal2);
  ASSERT_EQ(with.exit_code, 0) << with.err;
  const auto json = nlohmann::json::parse(with.out);
  EXPECT_EQ(json["model"], "idz");
  EXPECT_EQ(json["estimator"], "online");
  EXPECT_NEAR(json["area_m2"].get<double>() / kArea, 1.0, 0.10);  // measured +0.15 %
  EXPECT_GT(json["p22_s_per_m2"].get<double>(), 0.0);
  const ProgramRun without = Identify("asce2-pool2-prbs-fixed-gate", "--online --max-delay-s 1800");
  ASSERT_EQ(without.exit_code, 0) << without.err;
  const auto plain = nlohmann::json::parse(without.out);
  EXPECT_DOUBLE_EQ(plain["p22_s_per_m2"].get<double>(), 0.0);
  EXPECT_GT(plain["area_m2"].get<double>() / kArea, 1.15);  // measured +21 %
  const ProgramRun spread =
      Identify("asce2-pool2-prbs-fixed-gate", "--online --p22 0.0133 --p22-std 0.002");
  EXPECT_EQ(spread.exit_code, 2);
  EXPECT_NE(spread.err.find("--p22-std applies to the batch idz fit"), std::string::npos)
      << spread.err;
}

// `canalid simulate` runs the model JSON's level equation: on the record it was fitted on (level
// spikes kept, so both compare with the same level) it reproduces the fit's metrics.
TEST(IdzCli, SimulateReproducesTheModel) {
  const auto dir = TestDirectory("idz_cli_simulate");
  const std::string input =
      std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs-fixed-gate.csv";
  const ProgramRun run =
      RunProgram(CanalidProgram() + " identify --model idz --keep-outliers --input " + input +
                     kCanal2 + " --out " + (dir / "idz.json").string(),
                 dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectSimulateReproducesModel(dir / "idz.json", input, "level", dir);
}

TEST(IdzCli, PriorOptionsAreCheckedAndNamed) {
  auto expect_error = [](const ProgramRun& run, const std::string& text) {
    EXPECT_EQ(run.exit_code, 2) << run.out;
    EXPECT_NE(run.err.find(text), std::string::npos) << run.err;
  };
  expect_error(Identify("asce2-pool2-prbs", "--p22 0.01" + kCanal2),
               "--p22 and --canal both give the p22 prior");
  expect_error(Identify("asce2-pool2-prbs", "--p22-std 0.01"), "--p22-std needs a prior");
  expect_error(Identify("asce2-pool2-prbs", std::string("--canal ") + CANALID_SOURCE_DIR +
                                                "/config/sim/asce-canal2.toml --pool 12"),
               "--pool '12' is not a pool of");
  const auto dir = TestDirectory("idz_cli_id");
  const ProgramRun id = RunProgram(CanalidProgram() + " identify --model id --p22 0.01 --input " +
                                       CANALID_SOURCE_DIR + "/tests/data/sim/asce2-pool2-prbs.csv",
                                   dir);
  expect_error(id, "--p22 applies to --model idz and to --model id --online");
  const ProgramRun online =
      RunProgram(CanalidProgram() + " identify --model id --online" + kCanal2 + " --input " +
                     CANALID_SOURCE_DIR + "/tests/data/sim/asce2-pool2-prbs.csv",
                 dir);
  expect_error(online, "--canal applies to --model idz");
  expect_error(Identify("asce2-pool2-prbs", "--closed-loop off"), "--closed-loop applies to");
  // --p22 as the prior: the JSON says where it came from.
  const ProgramRun given = Identify("asce2-pool2-prbs-fixed-gate", "--p22 0.0133 --p22-std 0");
  ASSERT_EQ(given.exit_code, 0) << given.err;
  const auto json = nlohmann::json::parse(given.out);
  EXPECT_EQ(json["p22_prior"]["from"], "--p22");
  EXPECT_DOUBLE_EQ(json["p22_s_per_m2"].get<double>(), 0.0133);
  EXPECT_DOUBLE_EQ(json["p22_std_s_per_m2"].get<double>(), 0.0);
}

}  // namespace
}  // namespace canalid::testing
