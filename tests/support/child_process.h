#pragma once
// A program started by a test: its pid is kept, its stdout and stderr are read through one pipe
// (so the test can wait for a line with a bounded poll(2), never a sleep), and it is stopped by
// pid, with SIGKILL only if it ignores the signal for too long.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::testing {

class ChildProcess {
 public:
  /// Starts argv[0] with `argv` and the current environment plus `extra_env` ("NAME=value").
  /// Everything it prints is also appended to `log_path`, for the failure messages.
  ChildProcess(std::vector<std::string> argv, const std::vector<std::string>& extra_env,
               std::filesystem::path log_path)
      : log_(log_path, std::ios::trunc) {
    std::vector<char*> args;
    for (std::string& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    std::vector<std::string> env_storage;
    for (char** e = environ; *e != nullptr; ++e) env_storage.emplace_back(*e);
    env_storage.insert(env_storage.end(), extra_env.begin(), extra_env.end());
    std::vector<char*> env;
    for (std::string& e : env_storage) env.push_back(e.data());
    env.push_back(nullptr);
    int out[2];
    if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      dup2(out[1], STDERR_FILENO);
      execve(args[0], args.data(), env.data());
      _exit(127);
    }
    close(out[1]);
    fd_ = out[0];
  }
  ~ChildProcess() {
    if (pid_ > 0) Stop(SIGKILL, 5000);
    if (fd_ >= 0) close(fd_);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& output() const { return output_; }

  /// Reads until a line containing `text` appears after position `from` in the output, or the
  /// program exits, or `timeout_ms` passes.  Returns the line ("" when it did not come).
  std::string WaitForLine(const std::string& text, int timeout_ms, std::size_t from = 0) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      const std::size_t at = output_.find(text, from);
      if (at != std::string::npos) {
        const std::size_t begin = output_.rfind('\n', at);
        const std::size_t end = output_.find('\n', at);
        if (end != std::string::npos) {
          const std::size_t b = begin == std::string::npos ? 0 : begin + 1;
          return output_.substr(b, end - b);
        }
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0 || !ReadSome(static_cast<int>(left.count()))) return "";
    }
  }

  /// Sends `signal` and waits at most `timeout_ms` for the exit (then SIGKILL).  Returns the exit
  /// code, or 128 + the signal that ended it.
  int Stop(int signal = SIGTERM, int timeout_ms = 20000) {
    if (pid_ <= 0) return exit_code_;
    kill(pid_, signal);
    return WaitExit(timeout_ms);
  }

  /// Waits at most `timeout_ms` for the program to exit on its own (then SIGKILL), reading its
  /// output meanwhile.
  int WaitExit(int timeout_ms) {
    if (pid_ <= 0) return exit_code_;
    const int pidfd = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    bool exited = false;
    while (pidfd >= 0 && !exited) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      pollfd p[2] = {{pidfd, POLLIN, 0}, {fd_, POLLIN, 0}};
      if (poll(p, 2, static_cast<int>(left.count())) <= 0) break;
      if (p[1].revents != 0) ReadSome(0);
      exited = p[0].revents != 0;
    }
    if (!exited) kill(pid_, SIGKILL);
    if (pidfd >= 0) close(pidfd);
    int status = 0;
    waitpid(pid_, &status, 0);
    while (ReadSome(0)) {
    }
    pid_ = -1;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return exit_code_;
  }

 private:
  // One read after waiting at most timeout_ms; false at end of file or on a timeout.
  bool ReadSome(int timeout_ms) {
    if (fd_ < 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return false;
    char buffer[4096];
    const ssize_t got = read(fd_, buffer, sizeof buffer);
    if (got <= 0) return false;
    output_.append(buffer, static_cast<std::size_t>(got));
    log_.write(buffer, got);
    log_.flush();
    return true;
  }

  pid_t pid_ = -1;
  int fd_ = -1;
  int exit_code_ = -1;
  std::string output_;
  std::ofstream log_;
};

}  // namespace canalid::testing
