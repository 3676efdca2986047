#pragma once
// Test helpers: start `canalsim serve` on a free loopback port, wait for its ready line (bounded),
// stop it by pid with SIGTERM (bounded wait); and a small libmodbus TCP client.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::testing {

inline std::string CanalsimProgram() { return std::string(CANALID_BINARY_DIR) + "/sim/canalsim"; }
inline std::string SourcePath(const std::string& relative) {
  return std::string(CANALID_SOURCE_DIR) + "/" + relative;
}

/// A running `canalsim serve --listen 127.0.0.1:0 <args>`; the destructor stops it.
class ServeProcess {
 public:
  /// @param stderr_path where the server's stderr goes.
  /// Waits at most `ready_timeout_ms` for the ready line; throws if it does not come.
  ServeProcess(const std::vector<std::string>& args, const std::filesystem::path& stderr_path,
               int ready_timeout_ms = 60000) {
    // Everything the child needs is built before fork: only async-signal-safe calls after it
    // (the RTU test has a relay thread running).
    std::vector<std::string> all = {CanalsimProgram(), "serve", "--listen", "127.0.0.1:0"};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string err_path = stderr_path.string();
    int out[2];
    if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      const int err = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (err >= 0) dup2(err, STDERR_FILENO);
      execv(argv[0], argv.data());
      _exit(127);
    }
    close(out[1]);
    out_fd_ = out[0];
    try {
      WaitForReadyLine(ready_timeout_ms);
    } catch (...) {
      // Do not leave the server behind when it never became ready.
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
      close(out_fd_);
      out_fd_ = -1;
      throw;
    }
  }
  ~ServeProcess() {
    if (pid_ > 0) Stop();
    if (out_fd_ >= 0) close(out_fd_);
  }
  ServeProcess(const ServeProcess&) = delete;
  ServeProcess& operator=(const ServeProcess&) = delete;

  int port() const { return port_; }
  const std::string& ready_line() const { return ready_line_; }

  /// Sends `signal` (SIGTERM by default), then waits at most 20 s (SIGKILL after that).
  /// Returns the exit code, or 128 + signal if it was killed by one.
  int Stop(int signal = SIGTERM) {
    if (pid_ <= 0) return exit_code_;
    kill(pid_, signal);
    const int pidfd = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
    if (pidfd >= 0) {
      pollfd p{pidfd, POLLIN, 0};
      if (poll(&p, 1, 20000) <= 0) kill(pid_, SIGKILL);
      close(pidfd);
    }
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return exit_code_;
  }

 private:
  void WaitForReadyLine(int timeout_ms) {
    std::string line;
    // Bounded wait for "canalsim: listening on 127.0.0.1:PORT (...)".
    while (line.find('\n') == std::string::npos) {
      pollfd p{out_fd_, POLLIN, 0};
      if (poll(&p, 1, timeout_ms) <= 0) {
        throw std::runtime_error("canalsim serve printed no ready line in time");
      }
      char buffer[256];
      const ssize_t got = read(out_fd_, buffer, sizeof(buffer));
      if (got <= 0) throw std::runtime_error("canalsim serve exited before its ready line");
      line.append(buffer, static_cast<std::size_t>(got));
    }
    ready_line_ = line.substr(0, line.find('\n'));
    const std::string key = "listening on 127.0.0.1:";
    const std::size_t at = ready_line_.find(key);
    if (at == std::string::npos) throw std::runtime_error("unexpected line: " + ready_line_);
    port_ = std::stoi(ready_line_.substr(at + key.size()));
  }

  pid_t pid_ = -1;
  int out_fd_ = -1;
  int port_ = 0;
  int exit_code_ = -1;
  std::string ready_line_;
};

/// A libmodbus TCP master connected to 127.0.0.1:port.
class Master {
 public:
  explicit Master(int port, double timeout_s = 10.0) {
    ctx_ = modbus_new_tcp("127.0.0.1", port);
    if (ctx_ == nullptr) throw std::runtime_error("modbus_new_tcp failed");
    SetTimeout(timeout_s);
    if (modbus_connect(ctx_) != 0) throw std::runtime_error("modbus_connect failed");
  }
  ~Master() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  Master(const Master&) = delete;
  Master& operator=(const Master&) = delete;

  void SetTimeout(double timeout_s) {
    const auto s = static_cast<std::uint32_t>(timeout_s);
    const auto us = static_cast<std::uint32_t>((timeout_s - s) * 1e6);
    modbus_set_response_timeout(ctx_, s, us);
  }
  void Reconnect() {
    modbus_close(ctx_);
    if (modbus_connect(ctx_) != 0) throw std::runtime_error("modbus_connect failed");
  }
  /// Input registers [address, address + n); fails the test (and returns zeros) on an error.
  std::vector<std::uint16_t> Inputs(int address, int n) {
    std::vector<std::uint16_t> r(n, 0);
    const int rc = modbus_read_input_registers(ctx_, address, n, r.data());
    EXPECT_EQ(rc, n) << "read input " << address << ": " << modbus_strerror(errno);
    return r;
  }
  std::uint16_t Input(int address) { return Inputs(address, 1)[0]; }
  std::vector<std::uint16_t> Holdings(int address, int n) {
    std::vector<std::uint16_t> r(n, 0);
    const int rc = modbus_read_registers(ctx_, address, n, r.data());
    EXPECT_EQ(rc, n) << "read holding " << address << ": " << modbus_strerror(errno);
    return r;
  }
  std::uint16_t Holding(int address) { return Holdings(address, 1)[0]; }
  void Write(int address, std::uint16_t value) {
    EXPECT_EQ(modbus_write_register(ctx_, address, value), 1)
        << "write " << address << ": " << modbus_strerror(errno);
  }
  void WriteMany(int address, const std::vector<std::uint16_t>& values) {
    EXPECT_EQ(modbus_write_registers(ctx_, address, static_cast<int>(values.size()), values.data()),
              static_cast<int>(values.size()))
        << "write " << address << ": " << modbus_strerror(errno);
  }
  /// Lockstep: advance n plant steps (the reply comes after they are done).
  void Step(int n) { Write(1, static_cast<std::uint16_t>(n)); }
  /// A read that may fail: returns errno (0 on success).
  int TryReadInputs(int address, int n) {
    std::vector<std::uint16_t> r(n, 0);
    return modbus_read_input_registers(ctx_, address, n, r.data()) == n ? 0 : errno;
  }
  modbus_t* ctx() { return ctx_; }

 private:
  modbus_t* ctx_ = nullptr;
};

}  // namespace canalid::testing
