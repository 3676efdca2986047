// `canalid design` and `canalid identify --model arx` run as a user would run them.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

TEST(DesignCli, DesignsThePool2ExperimentAndWritesAFullPeriodPrbs) {
  const auto dir = TestDirectory("design");
  const auto csv = dir / "prbs.csv";
  const ProgramRun run = RunProgram(
      CanalidProgram() + " design --nominal-flow 10 --delay-s 682 --sample-time-s 60 --csv " +
          csv.string(),
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  // Domain rules: 7.5 % of 10 m3/s; clock ~ half of 682 s in whole 60 s samples; >= 5 delays.
  EXPECT_DOUBLE_EQ(json["amplitude"].get<double>(), 0.75);
  EXPECT_EQ(json["clock_period_samples"], 6);
  EXPECT_GE(json["duration_s"].get<double>(), 5 * 682.0);
  EXPECT_FALSE(json["explanation"].empty());
  // The CSV holds one full period: 2^n - 1 clocks, one more high clock than low ones.
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time_s,value");
  int high = 0, low = 0, rows = 0;
  while (std::getline(in, line)) {
    const double value = std::stod(line.substr(line.find(',') + 1));
    (value > 10.0 ? high : low)++;
    EXPECT_NEAR(std::abs(value - 10.0), 0.75, 1e-12);
    ++rows;
  }
  const int order = json["order"];
  EXPECT_EQ(rows, ((1 << order) - 1) * 6);
  EXPECT_EQ(high - low, 6);
}

TEST(DesignCli, RejectsAnAmplitudeOutsideTheRules) {
  const auto dir = TestDirectory("design-bad");
  const ProgramRun run = RunProgram(
      CanalidProgram() +
          " design --nominal-flow 10 --delay-s 682 --sample-time-s 60 --amplitude-percent 20",
      dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--amplitude-percent"), std::string::npos) << run.err;
}

// Octave's arx (control 3.4) on the same record: tests/data/octave, made by scripts/octave.
std::map<int, std::vector<double>> OctaveCoefficients(std::map<int, std::vector<int>>& orders) {
  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/tests/data/octave/arx_expected.csv");
  std::string line;
  std::getline(in, line);  // case,na,nb1,nb2,nk,first_sample,index,value
  std::map<int, std::vector<double>> values;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::vector<double> cells;
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(std::stod(cell));
    const int c = static_cast<int>(cells[0]);
    orders[c] = {static_cast<int>(cells[1]), static_cast<int>(cells[2]), static_cast<int>(cells[3]),
                 static_cast<int>(cells[4]), static_cast<int>(cells[5])};
    values[c].push_back(cells[7]);
  }
  return values;
}

TEST(ArxCli, AgreesWithOctaveArxWhereTheDataWindowsCoincide) {
  std::map<int, std::vector<int>> orders;
  const auto expected = OctaveCoefficients(orders);
  const auto dir = TestDirectory("arx-octave");
  int compared = 0;
  for (const auto& [c, theta] : expected) {
    const auto& o = orders.at(c);  // na, nb1, nb2, nk, first_sample
    // The CLI uses the first sample whose regressors all exist; Octave starts later when
    // na > nb + nk - 1 is not the binding term (see tests/core/arx_octave_test.cc).
    if (o[4] != std::max(o[0], std::max(o[1], o[2]) + o[3] - 1)) continue;
    const ProgramRun run =
        RunProgram(CanalidProgram() + " identify --model arx --input " + CANALID_SOURCE_DIR +
                       "/tests/data/octave/arx_input.csv --u u1,u2 --y y --na " +
                       std::to_string(o[0]) + " --nb " + std::to_string(o[1]) + "," +
                       std::to_string(o[2]) + " --nk " + std::to_string(o[3]),
                   dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto json = nlohmann::json::parse(run.out);
    std::vector<double> got = json["a"].get<std::vector<double>>();
    for (const auto& b : json["b_coeffs"]) {
      for (double v : b.get<std::vector<double>>()) got.push_back(v);
    }
    ASSERT_EQ(got.size(), theta.size()) << "case " << c;
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_NEAR(got[i], theta[i], 1e-6 * std::abs(theta[i]) + 1e-12)
          << "case " << c << " parameter " << i;
    }
    ++compared;
  }
  EXPECT_GE(compared, 2);
}

TEST(ArxCli, RejectsOrdersThatDoNotMatchTheInputs) {
  const auto dir = TestDirectory("arx-bad");
  const ProgramRun run =
      RunProgram(CanalidProgram() + " identify --model arx --input " + CANALID_SOURCE_DIR +
                     "/tests/data/octave/arx_input.csv --u u1,u2 --y y --nb 1,2,3",
                 dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--nb and --nk need one value, or one per input column (2)"),
            std::string::npos)
      << run.err;
}

}  // namespace
}  // namespace canalid::testing
