#pragma once
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::cli {

/// A helper program could not be started or failed: `canalid` prints it and exits 1.
class ToolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a child process ended: its exit status (128 + signal number when a signal ended it) and
/// what it wrote on stderr.
struct ChildResult {
  int exit_code = -1;
  std::string error_text;
};

/// Runs `program` (looked up in PATH unless it holds a '/') with `args` in `working_dir`, stdin
/// and stdout on /dev/null and stderr into the file `stderr_path`, and waits for it.
/// @throws ToolError if the program cannot be started (the message names it and the reason).
ChildResult RunChild(const std::string& program, const std::vector<std::string>& args,
                     const std::filesystem::path& working_dir,
                     const std::filesystem::path& stderr_path);

}  // namespace canalid::cli
