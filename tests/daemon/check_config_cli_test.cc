// canalidd's validation forms, run as a program: `canalidd --check-config FILE` (the documented
// form, docs/deployment.md and config/canalidd.example.toml) and `canalidd --config FILE
// --check-config` (the older one) both validate without starting anything; naming two different
// files is refused.  The truths: the exit codes (0 valid, 78 EX_CONFIG) and the file:line:column
// positions of the problems in the broken file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/child_process.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

// The TOML line `key = value` (value as written in the file).
std::string KeyLine(const std::string& key, const std::string& value) {
  return key + " = " + value;
}

namespace fs = std::filesystem;

constexpr int kExitConfig = 78;
constexpr int kTimeoutMs = 20000;  // validation only: well under a second when the box is idle

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
        if (line.rfind(KeyLine(key, ""), 0) == 0) {
          line = KeyLine(key, value);
          ++replaced;
        }
      }
      out << line << "\n";
    }
    EXPECT_EQ(replaced, static_cast<int>(all.size())) << "a key to replace is missing";
    fs::path path = dir_ / name;
    std::ofstream(path) << out.str();
    return path;
  }

  // Runs canalidd with `args` to completion; returns the exit code, output in `output`.
  // `as_nobody`: `program` (a copy of canalidd nobody can run) as user and group 65534 (setpriv,
  // from util-linux), for checks that root passes.
  int Run(const std::vector<std::string>& args, std::string& output, bool as_nobody = false,
          const std::string& program = DaemonProgram()) {
    std::vector<std::string> argv;
    if (as_nobody) {
      argv = {"/usr/bin/setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"};
    }
    argv.push_back(program);
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

// The key file is checked by --check-config with the same function as at start (ReadKeyFile), and
// each bad one makes both exit 78 (main said "valid" for these, then the daemon exited 70, so
// systemd's RestartPreventExitStatus=78 did not stop a restart loop).
TEST_F(CheckConfigCli, EveryBadKeyFileExits78InTheCheckAndAtStart) {
  const std::string hex(64, 'a');
  struct Variant {
    std::string name;
    std::string text;  // empty with mode 0: not made
    mode_t mode;
    std::string reason;
  };
  const std::vector<Variant> variants = {
      {"missing", "", 0, "cannot open"},
      {"empty", "", 0600, "is empty"},
      {"short", "0011223344\n", 0600, "10 hex digits"},
      {"mode-0644", hex + "\n", 0644, "chmod 600"},
      {"group-readable", hex + "\n", 0640, "chmod 600"},
      {"non-hex", std::string(63, 'a') + "z\n", 0600, "not a hex digit"},
      {"odd-length", hex.substr(0, 63) + "\n", 0600, "63 hex digits"},
      {"password-16", "Passw0rdPassw0rd\n", 0600, "not a hex digit"},
      {"hex-16", "0123456789abcdef\n", 0600, "16 hex digits"},
      {"trailing-garbage", hex + "\n# key\n", 0600, "not a hex digit"},
      {"too-long", hex + hex + "\n", 0600, "longer than a key"},
      {"directory", "", 0700, "not a regular file"},
      {"symlink-to-open", "", 0, "chmod 600"},
  };
  const fs::path keys = dir_ / "keys";
  fs::create_directories(keys);
  std::ofstream(keys / "open-target") << hex << "\n";
  ::chmod((keys / "open-target").c_str(), 0644);
  for (const Variant& v : variants) {
    const fs::path key = keys / v.name;
    if (v.name == "directory") {
      fs::create_directory(key);
    } else if (v.name == "symlink-to-open") {
      fs::create_symlink(keys / "open-target", key);
    } else if (v.mode != 0) {
      std::ofstream(key) << v.text;
      ::chmod(key.c_str(), v.mode);
    }
    const fs::path config =
        WriteConfig(v.name + ".toml", {{"enabled", "true\nkey_file = \"" + key.string() + "\""}});
    std::string output;
    EXPECT_EQ(Run({"--check-config", config.string()}, output), kExitConfig) << v.name << output;
    EXPECT_NE(output.find(key.string()), std::string::npos) << v.name << output;
    EXPECT_NE(output.find(v.reason), std::string::npos) << v.name << output;
    EXPECT_EQ(output.find(": valid"), std::string::npos) << v.name << output;
    EXPECT_EQ(Run({"--config", config.string()}, output), kExitConfig) << v.name << output;
    EXPECT_NE(output.find(v.reason), std::string::npos) << v.name << output;
  }
  // The same configuration with a good key is valid.
  const fs::path good_key = keys / "good";
  std::ofstream(good_key) << hex << "\n";
  ::chmod(good_key.c_str(), 0600);
  const fs::path good =
      WriteConfig("good.toml", {{"enabled", "true\nkey_file = \"" + good_key.string() + "\""}});
  std::string output;
  EXPECT_EQ(Run({"--check-config", good.string()}, output), 0) << output;
}

// A configured nominal near the actuator's limit: the check plans the demo's designed experiment
// around it as the daemon would, and warns that it has no room (the file stays valid: the daemon
// starts and refuses that experiment).  Around a nominal with room, no warning.
TEST_F(CheckConfigCli, AnExperimentWithoutRoomAroundTheConfiguredNominalIsWarned) {
  std::string output;
  // setpoint_max 2.0; the design's amplitude is 7.5 % of the nominal: 1.98 +- 0.1485 leaves it.
  // (The demo's file reads the nominal at start: the key is added after nominal_inflow_m3s.)
  const fs::path tight =
      WriteConfig("tight.toml", {{"nominal_inflow_m3s", "10.0\nnominal_setpoint = 1.98"}});
  EXPECT_EQ(Run({"--check-config", tight.string()}, output), 0) << output;
  EXPECT_NE(output.find("warning: reach pool2: experiment 'pool2_prbs' cannot run around the "
                        "configured nominal"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("leaves the actuator's [0.050000, 2.000000]"), std::string::npos) << output;
  EXPECT_NE(output.find(tight.string() + ": valid"), std::string::npos) << output;
  const fs::path roomy =
      WriteConfig("roomy.toml", {{"nominal_inflow_m3s", "10.0\nnominal_setpoint = 1.5"}});
  EXPECT_EQ(Run({"--check-config", roomy.string()}, output), 0) << output;
  EXPECT_EQ(output.find("warning:"), std::string::npos) << output;
}

TEST_F(CheckConfigCli, StateDirectoryIsCheckedBeforeStart) {
  std::string output;
  // Missing: the check notes it (systemd's StateDirectory= makes it at start), the start refuses.
  fs::remove_all(dir_ / "state");
  const fs::path config = WriteConfig("missing-state.toml", {});
  EXPECT_EQ(Run({"--check-config", config.string()}, output), 0) << output;
  EXPECT_NE(output.find("does not exist"), std::string::npos) << output;
  EXPECT_EQ(Run({"--config", config.string()}, output), kExitConfig) << output;
  EXPECT_NE(output.find("state directory " + (dir_ / "state").string() + " does not exist"),
            std::string::npos)
      << output;
  // A file where the directory should be: refused by both.
  std::ofstream(dir_ / "state") << "not a directory\n";
  EXPECT_EQ(Run({"--check-config", config.string()}, output), kExitConfig) << output;
  EXPECT_NE(output.find("is not a directory"), std::string::npos) << output;
  EXPECT_EQ(Run({"--config", config.string()}, output), kExitConfig) << output;
  // Not writable.
  fs::remove(dir_ / "state");
  fs::create_directory(dir_ / "state");
  ::chmod((dir_ / "state").c_str(), 0500);
  if (::geteuid() != 0) {
    EXPECT_EQ(Run({"--check-config", config.string()}, output), kExitConfig) << output;
  } else {
    // Root writes anywhere: the check runs as user nobody, on copies of the program and the file
    // in a folder under /tmp (the build tree may be closed to nobody: under /root in a fresh
    // Debian root), with a state directory that stays root's (mode 0755).
    std::string folder = "/tmp/canalid-check-config-XXXXXX";
    ASSERT_NE(::mkdtemp(folder.data()), nullptr);
    const fs::path open_dir = folder;
    ::chmod(open_dir.c_str(), 0755);
    fs::create_directory(open_dir / "state");
    ::chmod((open_dir / "state").c_str(), 0755);
    fs::copy_file(DaemonProgram(), open_dir / "canalidd");
    ::chmod((open_dir / "canalidd").c_str(), 0755);
    std::ifstream in(config);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string old_state = (dir_ / "state").string();
    ASSERT_NE(text.find(old_state), std::string::npos);
    text.replace(text.find(old_state), old_state.size(), (open_dir / "state").string());
    std::ofstream(open_dir / "config.toml") << text;
    ::chmod((open_dir / "config.toml").c_str(), 0644);
    EXPECT_EQ(Run({"--check-config", (open_dir / "config.toml").string()}, output, true,
                  (open_dir / "canalidd").string()),
              kExitConfig)
        << output;
    fs::remove_all(open_dir);
  }
  EXPECT_NE(output.find("not writable"), std::string::npos) << output;
  ::chmod((dir_ / "state").c_str(), 0700);
  EXPECT_EQ(Run({"--check-config", config.string()}, output), 0) << output;
}

}  // namespace
}  // namespace canalid::testing
