// The flume paper's experiment on config/sim/lab-flume.toml: canalsim runs the gate step scenario
// and `canalid identify --model foptd` fits it.  Truths: the flume paper's nominal model and the
// ranges of its 1080 experiments (shared/domain/README.md section 5), and the linearised flume
// model of its Eq. [14] with this file's numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "drivers/csv/csv_table.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

// canalsim run -q on config/sim/CANAL.toml and config/sim/scenarios/SCENARIO.toml, into csv.
ProgramRun RunScenario(const std::string& canal, const std::string& scenario,
                       const std::filesystem::path& csv, const std::filesystem::path& dir) {
  const std::string src = CANALID_SOURCE_DIR;
  return RunProgram(std::string(CANALID_BINARY_DIR) + "/sim/canalsim run -q" + " --canal " + src +
                        "/config/sim/" + canal + ".toml" + " --scenario " + src +
                        "/config/sim/scenarios/" + scenario + ".toml" + " --out " + csv.string(),
                    dir);
}

TEST(LabFlumeCli, GateStepFitsAFoptdOfTheOrderOfSeed2) {
  const auto dir = TestDirectory("lab-flume-foptd");
  const auto csv = dir / "gate-step.csv";
  const ProgramRun sim = RunScenario("lab-flume", "lab-flume-gate-step", csv, dir);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const drivers::CsvTable table = drivers::CsvTable::Read(csv.string());
  ASSERT_EQ(table.rows(), 2501);  // 375 s every 0.15 s, the paper's sample time
  EXPECT_NEAR(table.time_s()[1], 0.15, 1e-12);

  const ProgramRun fit = RunProgram(
      CanalidProgram() + " identify --model foptd --u u --y y --input " + csv.string(), dir);
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const nlohmann::json model = nlohmann::json::parse(fit.out);
  const double gain = model["gain"].get<double>();
  const double time_constant = model["time_constant_s"].get<double>();
  const double delay = model["delay_s"].get<double>();
  // Our flume approximates the flume paper's (reservoir size, Cw, a straight 1-D pool; measured
  // here: K 0.53, T 8.4 s, tau 3.1 s), so "of the order of" is: inside the ranges the flume paper
  // found over its 1080 experiments (K 0.086-0.775, T 1.1-48.94 s, tau 2.25-5.7 s), and within a
  // factor 1.5 of its nominal K0 = 0.372, T0 = 10.975 s, tau0 = 4.05 s.
  EXPECT_GT(gain, 0.086);
  EXPECT_LT(gain, 0.775);
  EXPECT_GT(gain, 0.372 / 1.5);
  EXPECT_LT(gain, 0.372 * 1.5);
  EXPECT_GT(time_constant, 10.975 / 1.5);
  EXPECT_LT(time_constant, 10.975 * 1.5);
  EXPECT_GT(delay, 2.25);
  EXPECT_LT(delay, 5.7);
  // Eq. [14] linearised with this flume (Cd 0.4, w 0.08 m, u 15 mm, heads 20 mm at the gate and
  // 17 mm over the crest, Cw 1.7, surface 4.7 x 0.08 m2): K = dQg/du / (dQw/dy + dQg/dy_dn) =
  // 0.0200 / (0.0266 + 0.0075) = 0.59 and T = 0.376 / 0.0341 = 11.0 s.  The Saint-Venant pool is
  // not a tank and the 5 mm step is not small, so 20 % on K and 30 % on T.
  EXPECT_NEAR(gain, 0.59, 0.20 * 0.59);
  EXPECT_NEAR(time_constant, 11.0, 0.30 * 11.0);
  EXPECT_GT(model["metrics"]["fit_percent"].get<double>(), 80.0);
}

TEST(PumpPilotCli, B1PrbsGivesAnIntegratorWithTheWaveTravelDelay) {
  // The LPV paper's experiment on pool P1 (PRBS on pump B1, the other pumps held).  The ID model's
  // delay must be the wave's travel time over the 12 m pool, L / (c + V) = 8.5 s at 20 cm,
  // within one 0.5 s sample either way: the LPV paper found 5-17 samples, 17 at its lowest level.
  // Its area must be of the order of the pool's 1.8 m2 surface: the reflected waves between the
  // pumps bias it (measured 2.3 m2), so only a factor 1.5 is asked.
  const auto dir = TestDirectory("pump-pilot-id");
  const auto csv = dir / "b1-prbs.csv";
  const ProgramRun sim = RunScenario("pump-pilot", "pump-pilot-b1-prbs", csv, dir);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const ProgramRun fit = RunProgram(
      CanalidProgram() + " identify --model id --max-delay-s 30 --input " + csv.string(), dir);
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const nlohmann::json model = nlohmann::json::parse(fit.out);
  const double travel = 12.0 / (std::sqrt(9.81 * 0.20) + 0.0002 / (0.15 * 0.20));
  EXPECT_NEAR(model["delay_s"].get<double>(), travel, 0.5) << model.dump();
  EXPECT_LE(model["delay_s"].get<double>(), 8.5);
  EXPECT_GT(model["area_m2"].get<double>(), 1.8 / 1.5);
  EXPECT_LT(model["area_m2"].get<double>(), 1.8 * 1.5);
}

}  // namespace
}  // namespace canalid::testing
