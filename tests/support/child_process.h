#pragma once
// The one way a test starts another program: its pid is kept, its stdout (and stderr, unless sent
// to a file) is read through a pipe, so the test waits for a line or a condition with a bounded
// poll(2) on that pipe and on a pidfd (never a sleep, and an exit ends the wait at once); it is
// stopped by pid with a signal (SIGTERM by default) and SIGKILL only after a bound.  Everything
// the child needs is built before fork(): only async-signal-safe calls after it, so tests with
// threads running may use it.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace canalid::testing {

/// How to start a child (ChildProcess).
struct ChildOptions {
  /// argv[0] is a path, or a name looked up in PATH (before the fork).
  std::vector<std::string> argv;
  /// Added to the current environment ("NAME=value").
  std::vector<std::string> extra_env;
  /// Empty: stderr joins stdout in output().  Else stderr goes to this file (truncated).
  std::filesystem::path stderr_path;
  /// Non-empty: everything read from the child is also written here, for failure messages.
  std::filesystem::path log_path;
  /// true: stdin is a pipe the test holds open until Stop (for programs that exit when their
  /// stdin closes); false: /dev/null.
  bool stdin_pipe = false;
};

class ChildProcess {
 public:
  /// Starts the program; throws std::runtime_error when it cannot be started (an exec failure
  /// shows as exit code 127).
  explicit ChildProcess(ChildOptions options) { Start(std::move(options)); }
  /// Starts argv[0] with `argv` and the current environment plus `extra_env`, stdout and stderr
  /// captured together and also written to `log_path`.
  ChildProcess(std::vector<std::string> argv, std::vector<std::string> extra_env,
               std::filesystem::path log_path) {
    ChildOptions options;
    options.argv = std::move(argv);
    options.extra_env = std::move(extra_env);
    options.log_path = std::move(log_path);
    Start(std::move(options));
  }
  ~ChildProcess() {
    if (pid_ > 0) Stop(SIGTERM, 5000);
    CloseFd(out_fd_);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// The pid while the child is not yet reaped, -1 after Stop or WaitExit.
  pid_t pid() const { return pid_; }
  /// Everything read from the child so far.
  const std::string& output() const { return output_; }
  /// The exit code (128 + signal when a signal ended it) once reaped, else -1.
  int exit_code() const { return exit_code_; }

  /// true until the child has exited (a stopped child is running; a zombie is not).
  bool Running() const {
    if (pid_ <= 0) return false;
    if (pidfd_ < 0) return kill(pid_, 0) == 0;
    pollfd p{pidfd_, POLLIN, 0};
    return poll(&p, 1, 0) == 0;
  }

  /// Reads until a line containing `text` appears after position `from` in the output, or the
  /// program exits, or `timeout_ms` passes.  Returns the line ("" when it did not come).
  std::string WaitForLine(const std::string& text, int timeout_ms, std::size_t from = 0) {
    std::string line;
    WaitUntil([&] { return !(line = FindLine(text, from)).empty(); }, timeout_ms, -1);
    return line;
  }

  /// Re-checks `ready` after every read of output, every `recheck_ms` (< 0: only on output) and
  /// when the child exits, until it holds or `timeout_ms` passes.  Returns whether it held.  For
  /// conditions outside the child (a port that accepts, a file written): the recheck interval
  /// only bounds the latency, the deadline bounds the wait.
  bool WaitUntil(const std::function<bool()>& ready, int timeout_ms, int recheck_ms = 20) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      if (ready()) return true;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return false;
      const int wait = recheck_ms < 0 ? static_cast<int>(left)
                                      : static_cast<int>(std::min<long>(left, recheck_ms));
      if (!WaitForActivity(wait) && !Running() && !ReadSome(0)) {
        // Exited and nothing left to read: nothing can change any more.
        return ready();
      }
    }
  }

  /// Reads what the child has written so far, without waiting. A child that logs for long while
  /// the test waits on something else blocks once its pipe is full (64 kB): call this meanwhile.
  void Drain() {
    while (ReadSome(0)) {
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
  /// output meanwhile.  Returns the exit code, or 128 + the signal that ended it.
  int WaitExit(int timeout_ms) {
    if (pid_ <= 0) return exit_code_;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (Running()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0 || pidfd_ < 0) break;
      WaitForActivity(static_cast<int>(left));
    }
    if (Running()) kill(pid_, SIGKILL);
    CloseFd(stdin_fd_);
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    while (ReadSome(0)) {
    }
    CloseFd(pidfd_);
    pid_ = -1;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return exit_code_;
  }

  /// The write end of the child's stdin (ChildOptions::stdin_pipe), else -1.
  int stdin_fd() const { return stdin_fd_; }

 private:
  void Start(ChildOptions options) {
    if (options.argv.empty()) throw std::invalid_argument("ChildProcess: empty argv");
    std::string program = options.argv[0];
    if (program.find('/') == std::string::npos) program = FindInPath(program);
    std::vector<char*> args;
    args.reserve(options.argv.size() + 1);
    for (std::string& a : options.argv) args.push_back(a.data());
    args.push_back(nullptr);
    std::vector<std::string> env_storage;
    for (char** e = environ; *e != nullptr; ++e) env_storage.emplace_back(*e);
    env_storage.insert(env_storage.end(), options.extra_env.begin(), options.extra_env.end());
    std::vector<char*> env;
    env.reserve(env_storage.size() + 1);
    for (std::string& e : env_storage) env.push_back(e.data());
    env.push_back(nullptr);
    const std::string err_path = options.stderr_path.string();
    if (!options.log_path.empty()) log_.open(options.log_path, std::ios::trunc);

    int out[2];
    int in[2] = {-1, -1};
    if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    if (options.stdin_pipe && pipe2(in, O_CLOEXEC) != 0) {
      close(out[0]);
      close(out[1]);
      throw std::runtime_error("pipe failed");
    }
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int in_fd = in[0] >= 0 ? in[0] : open("/dev/null", O_RDONLY);
      if (in_fd >= 0) dup2(in_fd, STDIN_FILENO);
      dup2(out[1], STDOUT_FILENO);
      const int err =
          err_path.empty() ? out[1] : open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (err >= 0) dup2(err, STDERR_FILENO);
      execve(program.c_str(), args.data(), env.data());
      _exit(127);
    }
    close(out[1]);
    out_fd_ = out[0];
    if (in[0] >= 0) {
      close(in[0]);
      stdin_fd_ = in[1];
    }
    // Not reaped yet, so the pid cannot be reused before this.
    pidfd_ = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
  }

  static std::string FindInPath(const std::string& name) {
    // getenv is not thread-safe against setenv; no test changes PATH.
    const char* path = std::getenv("PATH");  // NOLINT(concurrency-mt-unsafe)
    std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
    std::size_t begin = 0;
    while (begin <= dirs.size()) {
      std::size_t end = dirs.find(':', begin);
      if (end == std::string::npos) end = dirs.size();
      const std::filesystem::path candidate =
          std::filesystem::path(dirs.substr(begin, end - begin)) / name;
      if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
      begin = end + 1;
    }
    return name;  // execve fails: exit code 127
  }

  std::string FindLine(const std::string& text, std::size_t from) const {
    const std::size_t at = output_.find(text, from);
    if (at == std::string::npos) return "";
    const std::size_t begin = output_.rfind('\n', at);
    const std::size_t end = output_.find('\n', at);
    if (end == std::string::npos) return "";  // not complete yet
    const std::size_t b = begin == std::string::npos ? 0 : begin + 1;
    return output_.substr(b, end - b);
  }

  // Waits at most timeout_ms for output (read here) or the exit.  Returns whether output came.
  bool WaitForActivity(int timeout_ms) {
    // poll(2) ignores the entries whose fd is negative (closed output, no pidfd).
    if (out_fd_ < 0 && (pidfd_ < 0 || pid_ <= 0)) return false;
    pollfd p[2] = {{out_fd_, POLLIN, 0}, {pid_ > 0 ? pidfd_ : -1, POLLIN, 0}};
    if (poll(p, 2, timeout_ms) <= 0) return false;
    return p[0].revents != 0 && ReadSome(0);
  }

  // One read after waiting at most timeout_ms; false at end of file or on a timeout.
  bool ReadSome(int timeout_ms) {
    if (out_fd_ < 0) return false;
    pollfd p{out_fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return false;
    char buffer[4096];
    const ssize_t got = read(out_fd_, buffer, sizeof buffer);
    if (got <= 0) {
      CloseFd(out_fd_);  // end of file: every writer has exited
      return false;
    }
    output_.append(buffer, static_cast<std::size_t>(got));
    if (log_.is_open()) {
      log_.write(buffer, got);
      log_.flush();
    }
    return true;
  }

  static void CloseFd(int& fd) {
    if (fd >= 0) close(fd);
    fd = -1;
  }

  pid_t pid_ = -1;
  int pidfd_ = -1;
  int out_fd_ = -1;
  int stdin_fd_ = -1;
  int exit_code_ = -1;
  std::string output_;
  std::ofstream log_;
};

}  // namespace canalid::testing
