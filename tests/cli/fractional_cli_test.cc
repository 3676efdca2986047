// `canalid identify --model frac-foptd` and `--compare` on held-out gate-step experiments made
// from the exact Mittag-Leffler step response (core/fractional/mittag_leffler.h, independent of the
// Oustaloup simulator the fit uses), run through the real program.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/frac_gate_step.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

constexpr double kTs = 0.15;    // the flume paper's flume: Ts = 0.15 s
constexpr int kSamples = 2400;  // 360 s per experiment
constexpr double kNoiseMm = 0.15;
constexpr int kStepSample = 40;  // the gate moves at 6 s

using GateStep = FracGateStep;

// Inside the flume paper's ranges (K 0.086..0.775, T 1.17..48, tau 2.25..5.7 s, alpha 0.6..1.25),
// gate steps on its 5 mm grid giving level changes of 6..15 mm (40..100 sigma of the noise).
const std::vector<GateStep> kExperiments = {
    {0.372, 10.975, 4.05, 0.60, 20, 50}, {0.55, 6.0, 3.0, 0.70, 15, 40},
    {0.25, 20.0, 5.2, 0.90, 10, 50},     {0.45, 9.0, 2.5, 1.00, 45, 20},
    {0.70, 3.5, 3.6, 1.10, 30, 45},      {0.30, 15.0, 4.6, 1.25, 10, 50},
    {0.60, 4.0, 2.8, 0.75, 40, 15},      {0.15, 25.0, 5.5, 1.20, 10, 50},
};

// The experiment's record, its noise seeded with `seed`.
std::string StepCsv(const GateStep& e, unsigned seed) {
  return FracGateStepCsv(e, {kSamples, kStepSample, kTs, kNoiseMm, seed});
}

class FractionalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    // Suite and test: two suites have tests of the same name, and ctest runs them side by side.
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = TestDirectory(std::string(info->test_suite_name()) + "." + info->name());
  }
  // Writes every experiment as step_<i>.csv into `folder`.
  void WriteExperiments(const std::filesystem::path& folder) {
    std::filesystem::create_directories(folder);
    for (std::size_t i = 0; i < kExperiments.size(); ++i) {
      WriteFile(folder / ("step_" + std::to_string(i) + ".csv"),
                StepCsv(kExperiments[i], 100 + static_cast<unsigned>(i)));
    }
  }
  nlohmann::json Identify(const std::filesystem::path& csv, const std::string& model) {
    const ProgramRun run = RunProgram(CanalidProgram() + " identify --model " + model +
                                          " --u gate --y level --input " + csv.string(),
                                      dir_);
    EXPECT_EQ(run.exit_code, 0) << model << " " << csv << "\n" << run.err;
    return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json();
  }
  std::filesystem::path dir_;
};

TEST_F(FractionalCli, HeldOutGateStepsMeetIssue3sAccuracy) {
  WriteExperiments(dir_ / "steps");
  for (std::size_t i = 0; i < kExperiments.size(); ++i) {
    const GateStep& truth = kExperiments[i];
    const auto csv = dir_ / "steps" / ("step_" + std::to_string(i) + ".csv");
    const nlohmann::json frac = Identify(csv, "frac-foptd");
    ASSERT_EQ(frac["model"], "frac-foptd");
    // Issue 3's acceptance: alpha within 0.05, T within 10 %, K within 3 %, tau within 0.4 s.
    EXPECT_NEAR(frac["alpha"].get<double>(), truth.alpha, 0.05) << "case " << i;
    EXPECT_NEAR(frac["time_constant_s"].get<double>() / truth.time_constant_s, 1.0, 0.10)
        << "case " << i;
    EXPECT_NEAR(frac["gain"].get<double>() / truth.gain, 1.0, 0.03) << "case " << i;
    EXPECT_NEAR(frac["delay_s"].get<double>(), truth.delay_s, 0.4) << "case " << i;
    EXPECT_NEAR(frac["input_offset"].get<double>(), truth.gate_from_mm, 1e-12) << "case " << i;
    if (std::abs(truth.alpha - 1.0) < 0.25) continue;
    // Far from integer order the fractional model must beat both integer models clearly
    // (issue 3: norm_error at most 0.7 x the better of FOPTD and SOPTD).
    const double e_frac = frac["metrics"]["norm_error"].get<double>();
    const double e_foptd = Identify(csv, "foptd")["metrics"]["norm_error"].get<double>();
    const double e_soptd = Identify(csv, "soptd")["metrics"]["norm_error"].get<double>();
    EXPECT_LE(e_frac, 0.7 * std::min(e_foptd, e_soptd))
        << "case " << i << ": frac " << e_frac << " foptd " << e_foptd << " soptd " << e_soptd;
  }
}

TEST_F(FractionalCli, FixedAlphaIsKeptAndTheRestFitted) {
  const GateStep& truth = kExperiments[1];
  WriteFile(dir_ / "step.csv", StepCsv(truth, 7));
  const ProgramRun run = RunProgram(CanalidProgram() +
                                        " identify --model frac-foptd --u gate --y level "
                                        "--alpha 0.7 --input " +
                                        (dir_ / "step.csv").string(),
                                    dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_TRUE(json["alpha_fixed"].get<bool>());
  // Held to the fit's bound width (1e-9); with the true alpha the rest must meet the spec.
  EXPECT_NEAR(json["alpha"].get<double>(), 0.7, 1e-8);
  EXPECT_NEAR(json["time_constant_s"].get<double>() / truth.time_constant_s, 1.0, 0.10);
  EXPECT_NEAR(json["gain"].get<double>() / truth.gain, 1.0, 0.03);
}

// Splits the table's lines into whitespace-separated cells.
std::vector<std::vector<std::string>> Cells(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::vector<std::string> row;
    std::string word;
    while (words >> word) row.push_back(word);
    rows.push_back(row);
  }
  return rows;
}

TEST_F(FractionalCli, CompareOverAFolderPrintsSeed2sTable) {
  WriteExperiments(dir_ / "steps");
  // The glob is quoted: canalid expands it itself.
  const std::string command = CanalidProgram() + " identify --compare foptd,soptd,frac-foptd " +
                              "--u gate --y level --input '" + (dir_ / "steps").string() +
                              "/*.csv'";
  const ProgramRun table = RunProgram(command, dir_);
  ASSERT_EQ(table.exit_code, 0) << table.err;
  // Not a terminal: no progress on stderr.
  EXPECT_TRUE(table.err.empty()) << table.err;
  const auto rows = Cells(table.out);
  ASSERT_EQ(rows.size(), 5u) << table.out;  // title, header, three models
  EXPECT_NE(table.out.find("over 8 files"), std::string::npos) << table.out;
  EXPECT_EQ(rows[1], (std::vector<std::string>{"model", "mean", "max", "std"}));
  std::vector<double> means;
  for (std::size_t r = 2; r < 5; ++r) {
    ASSERT_EQ(rows[r].size(), 4u) << table.out;
    const double mean = std::stod(rows[r][1]), max = std::stod(rows[r][2]);
    const double sd = std::stod(rows[r][3]);
    // Sensible: at least the noise floor (0.15 mm over changes of 6..15 mm is 0.01..0.025),
    // small (every model follows a step), max >= mean, a spread.
    EXPECT_GT(mean, 0.009) << rows[r][0];
    EXPECT_LT(max, 0.2) << rows[r][0];
    EXPECT_GE(max, mean) << rows[r][0];
    EXPECT_GT(sd, 0.0) << rows[r][0];
    means.push_back(mean);
  }
  EXPECT_EQ(rows[2][0], "foptd");
  EXPECT_EQ(rows[3][0], "soptd");
  EXPECT_EQ(rows[4][0], "frac-foptd");
  // The flume paper's headline: the fractional model has the lowest mean error (its 11 % here is
  // more: half of these experiments are far from order 1).
  EXPECT_LT(means[2], 0.89 * std::min(means[0], means[1]));

  const ProgramRun json_run = RunProgram(command + " --json", dir_);
  ASSERT_EQ(json_run.exit_code, 0) << json_run.err;
  const auto json = nlohmann::json::parse(json_run.out);
  ASSERT_EQ(json["per_file"].size(), 8u);
  EXPECT_EQ(json["files"], 8);
  // The summary is the statistics of the per-file numbers (sample std, n - 1).
  for (const std::string kind : {"foptd", "soptd", "frac-foptd"}) {
    std::vector<double> values;
    for (const auto& f : json["per_file"]) values.push_back(f["norm_error"][kind].get<double>());
    double mean = 0.0, ss = 0.0;
    for (double v : values) mean += v / static_cast<double>(values.size());
    for (double v : values) ss += (v - mean) * (v - mean);
    EXPECT_NEAR(json["norm_error"][kind]["mean"].get<double>(), mean, 1e-12 * mean) << kind;
    EXPECT_NEAR(json["norm_error"][kind]["std"].get<double>(), std::sqrt(ss / 7.0), 1e-12) << kind;
    EXPECT_DOUBLE_EQ(json["norm_error"][kind]["max"].get<double>(),
                     *std::max_element(values.begin(), values.end()));
  }
  // The table and the JSON agree (the table prints 6 decimals).
  EXPECT_NEAR(json["norm_error"]["frac-foptd"]["mean"].get<double>(), means[2], 1e-6);
}

TEST_F(FractionalCli, CompareShowsProgressWhenStderrIsATerminal) {
  // util-linux script(1) gives the program a pseudo-terminal; its output is what the terminal
  // would show (the table goes to /dev/null).
  // NOLINTNEXTLINE(concurrency-mt-unsafe): std::system from the test's only thread
  ASSERT_EQ(std::system("command -v script >/dev/null 2>&1"), 0)
      << "no script(1) (Debian bsdutils)";
  WriteExperiments(dir_ / "steps");
  const std::string inner = CanalidProgram() + " identify --compare foptd --u gate --y level " +
                            "--input '" + (dir_ / "steps").string() + "/*.csv' >/dev/null";
  const ProgramRun run = RunProgram("script -qec \"" + inner + "\" /dev/null", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (int i = 1; i <= 8; ++i) {
    EXPECT_NE(run.out.find("file " + std::to_string(i) + "/8: "), std::string::npos) << run.out;
  }
}

// The process fits are the daemon's (core::FitProcessBatch): --max-delay-s bounds each one's
// delay. The gate step of a first-order lag (alpha 1, delay 2.5 s): every kind finds the delay
// past 2 s when allowed to (frac-ss up to 4.5 s: each candidate delay costs it a simulation of
// the whole record), and stays at or under 1.5 s when bounded there.
TEST_F(FractionalCli, MaxDelayBoundsEveryProcessFit) {
  WriteFile(dir_ / "step.csv", StepCsv(kExperiments[3], 1));
  const std::string input = " --u gate --y level --input " + (dir_ / "step.csv").string();
  for (const std::string kind : {"foptd", "soptd", "frac-foptd", "frac-ss"}) {
    for (const double max_delay_s : {4.5, 1.5}) {
      std::string command = CanalidProgram() + " identify --model " + kind;
      command += " --max-delay-s " + std::to_string(max_delay_s);
      command += input;
      const ProgramRun run = RunProgram(command, dir_);
      ASSERT_EQ(run.exit_code, 0) << kind << "\n" << run.err;
      const nlohmann::json json = nlohmann::json::parse(run.out);
      const double delay_s = json.at("delay_s").get<double>();
      EXPECT_LE(delay_s, max_delay_s + 1e-9) << kind;
      if (max_delay_s > 2.5) {
        EXPECT_GT(delay_s, 2.0) << kind;
      }
      EXPECT_EQ(json.at("sample_time_s").get<double>(), kTs) << kind;
    }
  }
}

TEST_F(FractionalCli, BadInputGetsOneClearMessageAndExitCode2) {
  WriteFile(dir_ / "step.csv", StepCsv(kExperiments[0], 1));
  const std::string csv = (dir_ / "step.csv").string();
  struct Case {
    std::string args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--model frac-foptd --u valve --y level --input " + csv, "no column 'valve'"},
      {"--model frac-foptd --u gate --y level --alpha 2.5 --input " + csv, "--alpha"},
      {"--model frac-ss --u gate --y level --q 3 --input " + csv, "--q"},
      {"--model frac-ss --u gate --y level --alpha 0.5 --input " + csv, "--alpha"},
      {"--model foptd --u gate --y level --q 2 --input " + csv,
       "--q applies to --model frac-ss, not foptd"},
      {"--model soptd --u gate --y level --alpha 0.8 --input " + csv,
       "--alpha applies to --model frac-foptd"},
      {"--compare foptd,id --u gate --y level --input " + csv, "'id' is not a kind"},
      {"--compare foptd --input '" + (dir_ / "none").string() + "/*.csv'", "no file matches"},
      {"--model foptd --compare foptd --input " + csv, "excludes"},
      {"--u gate --y level --input " + csv, "give --model KIND or --compare KINDS"},
  };
  for (const Case& c : cases) {
    const ProgramRun run = RunProgram(CanalidProgram() + " identify " + c.args, dir_);
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.err;
    EXPECT_NE(run.err.find(c.message), std::string::npos)
        << "expected '" << c.message << "' in: " << run.err;
    EXPECT_TRUE(run.out.empty()) << run.out;
  }
}

}  // namespace
}  // namespace canalid::testing
