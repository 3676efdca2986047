#pragma once
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "tests/support/child_process.h"

namespace canalid::testing {

/// Result of running a program to completion.
struct ProgramRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// A fresh directory under the build tree for one test's files.
inline std::filesystem::path TestDirectory(const std::string& name) {
  auto dir = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

/// Runs `command` through the shell (a ChildProcess: stdin /dev/null, stdout also written to
/// dir/stdout.txt, stderr to dir/stderr.txt) to completion, with no time limit of its own.
inline ProgramRun RunProgram(const std::string& command, const std::filesystem::path& dir) {
  ChildOptions options;
  options.argv = {"/bin/sh", "-c", command};
  options.log_path = dir / "stdout.txt";
  options.stderr_path = dir / "stderr.txt";
  ChildProcess child(options);
  ProgramRun run;
  run.exit_code = child.WaitExit(std::numeric_limits<int>::max());
  run.out = child.output();
  run.err = ReadFile(options.stderr_path);
  return run;
}

/// RunProgram with a time limit of the test's own: the child is killed after `seconds` (coreutils
/// timeout, exit code 124, which also stops what the command started), so a regression that hangs
/// fails instead of stalling the suite.
inline ProgramRun RunProgramWithin(const std::string& command, const std::filesystem::path& dir,
                                   int seconds) {
  return RunProgram("timeout --kill-after=5 " + std::to_string(seconds) + " " + command, dir);
}

/// The canalid program of this build.
inline std::string CanalidProgram() {
  return std::string(CANALID_BINARY_DIR) + "/daemon/canalid/canalid";
}

/// The canalidd daemon of this build.
inline std::string DaemonProgram() {
  return std::string(CANALID_BINARY_DIR) + "/daemon/canalidd/canalidd";
}

/// The canalid-command program of this build.
inline std::string CommandProgram() {
  return std::string(CANALID_BINARY_DIR) + "/daemon/command/canalid-command";
}

}  // namespace canalid::testing
