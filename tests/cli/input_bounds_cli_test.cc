// Hostile inputs that crashed or hung `canalid` (issue: 10 CLI crashes and a hang): each runs the
// real program with the input that caused it and expects exit 2 with stderr naming the problem.
// Every run has its own time limit (RunProgramWithin), so a hang fails the test.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

constexpr int kSeconds = 60;

// A step through 0.5 / (1 + 20 s) sampled every `ts` seconds (u, y).
std::string StepCsv(double ts, int rows) {
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u,y\n";
  double y = 0.0;
  for (int k = 0; k < rows; ++k) {
    const double u = k < 10 ? 0.0 : 1.0;
    csv << k * ts << "," << u << "," << y << "\n";
    y += (0.5 * u - y) * (1.0 - std::exp(-ts / 20.0));
  }
  return csv.str();
}

class InputBoundsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    // Suite and test: two suites have tests of the same name, and ctest runs them side by side.
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = TestDirectory(std::string(info->test_suite_name()) + "." + info->name());
    WriteFile(dir_ / "step.csv", StepCsv(1.0, 200));
  }
  ProgramRun Canalid(const std::string& args) {
    return RunProgramWithin(CanalidProgram() + " " + args, dir_, kSeconds);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  // Writes `model` and simulates it on `csv`; out.csv must not appear.
  ProgramRun Simulate(const nlohmann::json& model, const std::string& csv) {
    WriteFile(dir_ / "m.json", model.dump());
    ProgramRun run = Canalid("simulate --model-json " + Path("m.json") + " --input " + Path(csv) +
                             " --out " + Path("out.csv"));
    EXPECT_FALSE(std::filesystem::exists(dir_ / "out.csv")) << ReadFile(dir_ / "out.csv");
    return run;
  }
  std::filesystem::path dir_;
};

#define EXPECT_INPUT_ERROR(run, text)                                    \
  do {                                                                   \
    const ProgramRun r_ = (run);                                         \
    EXPECT_EQ(r_.exit_code, 2) << r_.err;                                \
    EXPECT_NE(r_.err.find(text), std::string::npos) << r_.err << r_.out; \
  } while (0)

// SIGSEGV: DelayedZoh cast delay / Ts to int (1e12 s at 1 s = 1e12 samples wrapped negative).
TEST_F(InputBoundsCli, ProcessModelDelayBeyondTheBound) {
  for (const std::string kind : {"foptd", "soptd"}) {
    SCOPED_TRACE(kind);
    nlohmann::json model = {{"model", kind}, {"gain", 0.5}, {"delay_s", 1e12}};
    if (kind == "foptd") model["time_constant_s"] = 20.0;
    if (kind == "soptd") model["time_constants_s"] = {20.0, 5.0};
    EXPECT_INPUT_ERROR(Simulate(model, "step.csv"), "samples must be in [0, 1e7]");
  }
}

// SIGSEGV: a record with 6e-8 s steps makes a 150 s delay 2.5e9 samples (beyond int).
TEST_F(InputBoundsCli, TinySampleTimeMakesTheDelayTooManySamples) {
  WriteFile(dir_ / "fast.csv", StepCsv(6e-8, 50));
  const nlohmann::json model = {
      {"model", "foptd"}, {"gain", 0.5}, {"time_constant_s", 20.0}, {"delay_s", 150.0}};
  EXPECT_INPUT_ERROR(Simulate(model, "fast.csv"), "samples must be in [0, 1e7]");
}

// SIGSEGV: --nk 2147483647 overflowed nb + nk - 1 in ArxOrders::min_first_sample.
TEST_F(InputBoundsCli, ArxDelayOrderOverflow) {
  EXPECT_INPUT_ERROR(
      Canalid("identify --model arx --input " + Path("step.csv") + " --nk 2147483647"),
      "ArxOrders.nk[0] = 2147483647 is out of range (allowed: 0..10000000)");
  // --nb 2147483647: na + sum(nb) wrapped to 0 and was reported as "needs a parameter".
  EXPECT_INPUT_ERROR(
      Canalid("identify --model arx --input " + Path("step.csv") + " --nb 2147483647"),
      "ArxOrders.nb[0] = 2147483647 is out of range (allowed: 0..1000)");
}

// Hang: "sections_per_decade": 1000 built a ~8000-state Oustaloup simulator (minutes per run);
// 1e9 overflowed the section count to 1 and simulated a wrong model with exit 0.
TEST_F(InputBoundsCli, OustaloupSectionsAreBounded) {
  for (const double density : {1000.0, 1e9}) {
    SCOPED_TRACE(density);
    const nlohmann::json model = {{"model", "frac-foptd"},
                                  {"gain", 0.5},
                                  {"time_constant_s", 20.0},
                                  {"alpha", 0.8},
                                  {"delay_s", 2.0},
                                  {"oustaloup",
                                   {{"low_frequency_rad_s", 4e-8},
                                    {"high_frequency_rad_s", 5.0},
                                    {"sections_per_decade", density}}}};
    EXPECT_INPUT_ERROR(Simulate(model, "step.csv"),
                       "key 'sections_per_decade': " + std::to_string(density) +
                           " is out of range (allowed: > 0 and <= 20)");
  }
  // Within the density bound, a band of 200 decades is still too many sections.
  const nlohmann::json wide = {{"model", "frac-foptd"},
                               {"gain", 0.5},
                               {"time_constant_s", 20.0},
                               {"alpha", 0.8},
                               {"delay_s", 2.0},
                               {"oustaloup",
                                {{"low_frequency_rad_s", 1e-100},
                                 {"high_frequency_rad_s", 1e100},
                                 {"sections_per_decade", 3.0}}}};
  EXPECT_INPUT_ERROR(Simulate(wide, "step.csv"), "(allowed: 1..200)");
}

// The LPV reader sized the coefficient matrix from "degree" before reading the lists.
TEST_F(InputBoundsCli, LpvDegreeIsCheckedBeforeUse) {
  const nlohmann::json model = {{"model", "lpv"},
                                {"kind", "first_order_arx"},
                                {"local_model", "arx"},
                                {"schedule", "y"},
                                {"degree", 100000000},
                                {"parameters", {"a1", "b1", "nk"}},
                                {"coefficients", {{"a1", {-0.9}}}}};
  EXPECT_INPUT_ERROR(Simulate(model, "step.csv"),
                     "key 'degree': 100000000 is out of range (allowed: 0..20)");
}

// An unstable ARX model wrote a CSV of inf and nan rows with exit 0.
TEST_F(InputBoundsCli, NonFiniteSimulationIsAnErrorAndWritesNothing) {
  const nlohmann::json model = {{"model", "arx"}, {"na", 1},       {"nb", {1}},
                                {"nk", {1}},      {"a", {-1e200}}, {"b_coeffs", {{1.0}}},
                                {"inputs", {"u"}}};
  EXPECT_INPUT_ERROR(Simulate(model, "step.csv"),
                     "(model 'arx'): the simulated output is inf from row 13 (time_s 13.000000)");
}

// NaN passed CLI::PositiveNumber and CLI::Range (every comparison with NaN is false).
TEST_F(InputBoundsCli, NanOptionsAreRejected) {
  const std::string identify = "identify --input " + Path("step.csv") + " ";
  EXPECT_INPUT_ERROR(Canalid(identify + "--model id --qin u --qout u --level y --max-delay-s nan"),
                     "--max-delay-s: nan is out of range (allowed: a finite number in (0, 1e+09]");
  EXPECT_INPUT_ERROR(Canalid(identify + "--model frac-foptd --alpha nan"),
                     "--alpha: nan is out of range");
  EXPECT_INPUT_ERROR(Canalid(identify + "--model id --online --p22 nan"),
                     "--p22: nan is out of range");
  EXPECT_INPUT_ERROR(Canalid("design --nominal-flow nan --delay-s 600 --sample-time-s 10"),
                     "--nominal-flow: nan is out of range");
}

// --max-delay-s 1e300 s was cast to int unchecked (1e299 samples).
TEST_F(InputBoundsCli, MaxDelayBeyondTheRecordIsAnError) {
  const std::string identify = "identify --input " + Path("step.csv") + " ";
  EXPECT_INPUT_ERROR(
      Canalid(identify + "--model id --qin u --qout u --level y --max-delay-s 1e300"),
      "--max-delay-s: 1e300 is out of range");
  EXPECT_INPUT_ERROR(Canalid(identify + "--model frac-ss --max-delay-s 1e6"),
                     "--max-delay-s 1000000.000000 s is 1000000.000000 samples");
}

}  // namespace
}  // namespace canalid::testing
