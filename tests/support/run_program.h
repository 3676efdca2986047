#pragma once
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace canalid::testing {

/// Result of running a program to completion.
struct ProgramRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// A fresh directory under the build tree for one test's files.
inline std::filesystem::path TestDirectory(const std::string& name) {
  const auto dir = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / name;
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

/// Runs `command` through the shell with stdout and stderr captured in files of `dir`; the
/// program runs to completion (no timing involved).
inline ProgramRun RunProgram(const std::string& command, const std::filesystem::path& dir) {
  const auto out = dir / "stdout.txt";
  const auto err = dir / "stderr.txt";
  const std::string full = command + " >" + out.string() + " 2>" + err.string() + " </dev/null";
  const int status = std::system(full.c_str());
  ProgramRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

/// RunProgram with a time limit of the test's own: the child is killed after `seconds` (coreutils
/// timeout, exit code 124), so a regression that hangs fails instead of stalling the suite.
inline ProgramRun RunProgramWithin(const std::string& command, const std::filesystem::path& dir,
                                   int seconds) {
  return RunProgram("timeout --kill-after=5 " + std::to_string(seconds) + " " + command, dir);
}

/// The canalid program of this build.
inline std::string CanalidProgram() {
  return std::string(CANALID_BINARY_DIR) + "/daemon/canalid/canalid";
}

}  // namespace canalid::testing
