// canalidd's validation forms, run as a program: `canalidd --check-config FILE` (the documented
// form, docs/deployment.md and config/canalidd.example.toml) and `canalidd --config FILE
// --check-config` (the older one) both validate without starting anything; naming two different
// files is refused.  The truths: the exit codes (0 valid, 78 EX_CONFIG) and the file:line:column
// positions of the problems in the broken file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/child_process.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kExitConfig = 78;
constexpr int kTimeoutMs = 20000;  // validation only: well under a second when the box is idle

std::string DaemonProgram() {
  return std::string(CANALID_BINARY_DIR) + "/daemon/canalidd/canalidd";
}

class CheckConfigCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CANALID_BINARY_DIR) / "test-output" / "check_config_cli" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "state");
  }

  // config/canalidd-asce2.toml (the demo's valid file) with its state directory in the test's
  // folder and whole lines `key = ...` replaced.
  fs::path WriteConfig(const std::string& name,
                       const std::vector<std::pair<std::string, std::string>>& keys) {
    std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/config/canalidd-asce2.toml");
    std::vector<std::pair<std::string, std::string>> all = keys;
    all.emplace_back("state_directory", "\"" + (dir_ / "state").string() + "\"");
    std::ostringstream out;
    std::string line;
    int replaced = 0;
    while (std::getline(in, line)) {
      for (const auto& [key, value] : all) {
        if (line.rfind(key + " = ", 0) == 0) {
          line = key + " = " + value;
          ++replaced;
        }
      }
      out << line << "\n";
    }
    EXPECT_EQ(replaced, static_cast<int>(all.size())) << "a key to replace is missing";
    const fs::path path = dir_ / name;
    std::ofstream(path) << out.str();
    return path;
  }

  // Runs canalidd with `args` to completion; returns the exit code, output in `output`.
  int Run(const std::vector<std::string>& args, std::string& output) {
    std::vector<std::string> argv = {DaemonProgram()};
    argv.insert(argv.end(), args.begin(), args.end());
    ChildProcess child(argv, {}, dir_ / "canalidd.log");
    const int code = child.WaitExit(kTimeoutMs);
    output = child.output();
    return code;
  }

  fs::path dir_;
};

TEST_F(CheckConfigCli, ShortFormAcceptsAValidFile) {
  const fs::path good = WriteConfig("good.toml", {});
  std::string output;
  EXPECT_EQ(Run({"--check-config", good.string()}, output), 0) << output;
  EXPECT_NE(output.find(good.string() + ": valid"), std::string::npos) << output;
}

TEST_F(CheckConfigCli, ShortFormReportsEveryProblemWithItsPosition) {
  const fs::path bad = WriteConfig("bad.toml", {{"port", "70000"}, {"poll_period_s", "-1.0"}});
  std::string output;
  EXPECT_EQ(Run({"--check-config", bad.string()}, output), kExitConfig) << output;
  // file:LINE:COLUMN: key.path: problem, one line per problem.
  std::istringstream lines(output);
  std::string line;
  std::vector<std::string> positioned;
  while (std::getline(lines, line)) {
    if (line.rfind(bad.string() + ":", 0) != 0) continue;
    const std::string rest = line.substr(bad.string().size() + 1);
    std::size_t digits = 0;
    EXPECT_GT(std::stoi(rest, &digits), 0) << line;
    EXPECT_EQ(rest[digits], ':') << line;
    positioned.push_back(rest);
  }
  ASSERT_EQ(positioned.size(), 2u) << output;
  EXPECT_NE(output.find("plc[0].port"), std::string::npos) << output;
  EXPECT_NE(output.find("plc[0].poll_period_s"), std::string::npos) << output;
  EXPECT_EQ(output.find(": valid"), std::string::npos) << output;
}

TEST_F(CheckConfigCli, LongFormStillValidates) {
  const fs::path good = WriteConfig("good.toml", {});
  const fs::path bad = WriteConfig("bad.toml", {{"port", "70000"}});
  std::string output;
  EXPECT_EQ(Run({"--config", good.string(), "--check-config"}, output), 0) << output;
  EXPECT_NE(output.find(good.string() + ": valid"), std::string::npos) << output;
  // The flag first, then the file: "--config" is not taken as --check-config's file.
  EXPECT_EQ(Run({"--check-config", "--config", good.string()}, output), 0) << output;
  EXPECT_EQ(Run({"--config", bad.string(), "--check-config"}, output), kExitConfig) << output;
  EXPECT_NE(output.find("plc[0].port"), std::string::npos) << output;
  // The same file named both ways is one file, not a conflict.
  EXPECT_EQ(Run({"--config", good.string(), "--check-config", good.string()}, output), 0) << output;
}

TEST_F(CheckConfigCli, TwoDifferentFilesAreRefused) {
  const fs::path a = WriteConfig("a.toml", {});
  const fs::path b = WriteConfig("b.toml", {});
  std::string output;
  EXPECT_EQ(Run({"--config", a.string(), "--check-config", b.string()}, output), kExitConfig)
      << output;
  EXPECT_NE(output.find("name different files"), std::string::npos) << output;
  EXPECT_NE(output.find(a.string()), std::string::npos) << output;
  EXPECT_NE(output.find(b.string()), std::string::npos) << output;
  EXPECT_EQ(output.find(": valid"), std::string::npos) << output;
}

TEST_F(CheckConfigCli, NoFileAndHelp) {
  std::string output;
  EXPECT_EQ(Run({}, output), kExitConfig) << output;
  EXPECT_NE(output.find("--check-config FILE"), std::string::npos) << output;
  EXPECT_EQ(Run({"--help"}, output), 0) << output;
  EXPECT_NE(output.find("--check-config"), std::string::npos) << output;
  EXPECT_NE(output.find("canalidd --check-config FILE"), std::string::npos) << output;
}

}  // namespace
}  // namespace canalid::testing
