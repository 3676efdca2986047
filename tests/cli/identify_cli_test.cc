// Runs the real `canalid` program on CSV files, as a user would.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

// ID-model data of ASCE canal 2 pool 2 (A = 34113 m2, 11 samples of 60 s delay), written with
// full precision.
std::string IdCsv(int n) {
  std::mt19937 rng(4);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,q_in,q_out,level\n";
  std::vector<double> q_in(static_cast<std::size_t>(n));
  double y = 2.1, value = 10.0;
  for (std::size_t k = 0; k < q_in.size(); ++k) {
    if (k % 6 == 0) value = 10.0 + ((rng() & 1U) ? 0.8 : -0.8);
    q_in[k] = value;
    if (k > 0) y += 60.0 / 34113.0 * ((k >= 11 ? q_in[k - 11] : q_in[0]) - 10.0);
    csv << 60.0 * static_cast<double>(k) << "," << q_in[k] << ",10," << y << "\n";
  }
  return csv.str();
}

class IdentifyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    // Suite and test: two suites have tests of the same name, and ctest runs them side by side.
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = TestDirectory(std::string(info->test_suite_name()) + "." + info->name());
  }
  ProgramRun Identify(const std::string& csv_text, const std::string& args) {
    WriteFile(dir_ / "in.csv", csv_text);
    return RunProgram(
        CanalidProgram() + " identify --input " + (dir_ / "in.csv").string() + " " + args, dir_);
  }
  std::string Csv() const { return (dir_ / "in.csv").string(); }
  std::filesystem::path dir_;
};

TEST_F(IdentifyCli, IdModelPrintsOneJsonObjectWithTheDesignKeys) {
  const ProgramRun run = Identify(IdCsv(840), "--model id --max-delay-s 2400");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["model"], "id");
  EXPECT_EQ(json["nk"], 11);
  EXPECT_DOUBLE_EQ(json["delay_s"].get<double>(), 660.0);
  EXPECT_NEAR(json["area_m2"].get<double>(), 34113.0, 1e-6 * 34113.0);
  EXPECT_NEAR(json["b"].get<double>(), 60.0 / 34113.0, 1e-9);
  EXPECT_DOUBLE_EQ(json["sample_time_s"].get<double>(), 60.0);
  for (const char* key : {"rmse", "mae", "fit_percent", "ise", "norm_error"}) {
    EXPECT_TRUE(json["metrics"].contains(key)) << key;
  }
}

TEST_F(IdentifyCli, BadInputGetsOneClearMessageAndExitCode2) {
  struct Case {
    std::string csv;
    std::string args;
    std::string message;  // what stderr must contain, besides the file name
  };
  const std::string ok_header = "time_s,q_in,q_out,level\n";
  const std::vector<Case> cases = {
      {ok_header + "0,1,1,2\n60,1,1,2\n", "--model id --qin flow", "no column 'flow'"},
      {ok_header + "0,1,1,2\n60,x,1,2\n", "--model id", ":3: column 'q_in': 'x' is not a number"},
      {ok_header + "0,1,1,2\n60,1,1,2\n30,1,1,2\n", "--model id",
       ":4: time_s 30 does not increase"},
      {ok_header + "0,1,1,2\n60,1,1,2\n180,1,1,2\n", "--model id",
       ":4: time_s 180 breaks uniform sampling"},
      {ok_header + "0,1,1,2\n60,1,1,nan\n", "--model id",
       ":3: column 'level': 'nan' is not finite"},
      {ok_header + "0,1,1,2\n60,2,1,2\n120,1,1,2\n", "--model id", "needs at least 20 samples"},
      {IdCsv(200).replace(0, 0, ""), "--model id --qin q_out", "column 'q_out' never moves"},
  };
  for (const Case& c : cases) {
    const ProgramRun run = Identify(c.csv, c.args);
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.err;
    EXPECT_NE(run.err.find(Csv()), std::string::npos) << run.err;
    EXPECT_NE(run.err.find(c.message), std::string::npos)
        << "expected '" << c.message << "' in: " << run.err;
    EXPECT_TRUE(run.out.empty()) << run.out;
  }
}

TEST_F(IdentifyCli, MissingFileAndUnknownModelAreRejected) {
  ProgramRun run =
      RunProgram(CanalidProgram() + " identify --model id --input /nonexistent.csv", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("/nonexistent.csv: cannot open file"), std::string::npos) << run.err;
  run = RunProgram(CanalidProgram() + " identify --model magic --input x.csv", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("magic"), std::string::npos) << run.err;
}

TEST_F(IdentifyCli, EveryCommandHasHelp) {
  for (const std::string command : {"", " identify"}) {
    const ProgramRun run = RunProgram(CanalidProgram() + command + " --help", dir_);
    EXPECT_EQ(run.exit_code, 0) << command;
    EXPECT_NE(run.out.find("Usage:"), std::string::npos) << command;
  }
}

TEST_F(IdentifyCli, FoptdFromAStepRecord) {
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u,y\n";
  for (int k = 0; k < 2400; ++k) {
    const double t = 0.15 * k, s = t - 6.0 - 4.05;  // step at 6 s, delay 4.05 s
    csv << t << "," << (t >= 6.0 ? 0.25 : 0.2) << ","
        << 0.3 + (s > 0 ? 0.372 * 0.05 * (1 - std::exp(-s / 10.975)) : 0.0) << "\n";
  }
  const ProgramRun run = Identify(csv.str(), "--model foptd");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["model"], "foptd");
  EXPECT_NEAR(json["gain"].get<double>(), 0.372, 1e-6);
  EXPECT_NEAR(json["time_constant_s"].get<double>(), 10.975, 1e-5);
  EXPECT_NEAR(json["delay_s"].get<double>(), 4.05, 1e-6);
}

}  // namespace
}  // namespace canalid::testing
