#pragma once
// Test helpers: start `canalsim serve` on a free loopback port, wait for its ready line (bounded),
// stop it by pid with SIGTERM (bounded wait); and a small libmodbus TCP client.
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <signal.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/child_process.h"

namespace canalid::testing {

inline std::string CanalsimProgram() { return std::string(CANALID_BINARY_DIR) + "/sim/canalsim"; }
inline std::string SourcePath(const std::string& relative) {
  return std::string(CANALID_SOURCE_DIR) + "/" + relative;
}

/// config/sim/plc/asce2.toml written to `dir`/plc.toml with the PLC's heartbeat watchdog set to
/// `timeout` plant seconds (for runs that are not about the watchdog, at time scales where its
/// 300 s would be a fraction of a wall second).  Returns the path; empty when the shipped file no
/// longer has the line this replaces.
inline std::filesystem::path Asce2PlcWithWatchdog(const std::filesystem::path& dir,
                                                  const std::string& timeout) {
  std::ifstream in(SourcePath("config/sim/plc/asce2.toml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string plc = text.str();
  const std::string watchdog = "heartbeat_timeout_s = 300.0";
  const std::size_t at = plc.find(watchdog);
  if (at == std::string::npos) return {};
  plc.replace(at, watchdog.size(), "heartbeat_timeout_s = " + timeout);
  std::filesystem::path path = dir / "plc.toml";
  std::ofstream(path) << plc;
  return path;
}

/// A running `canalsim serve --listen 127.0.0.1:0 <args>` (a ChildProcess); the destructor stops
/// it.
class ServeProcess {
 public:
  /// @param stderr_path where the server's stderr goes.
  /// Waits at most `ready_timeout_ms` for the ready line; throws if it does not come (the server
  /// is stopped first).
  ServeProcess(const std::vector<std::string>& args, const std::filesystem::path& stderr_path,
               int ready_timeout_ms = 60000)
      : child_(Options(args, stderr_path)) {
    // "canalsim: listening on 127.0.0.1:PORT (...)"
    const std::string key = "listening on 127.0.0.1:";
    ready_line_ = child_.WaitForLine(key, ready_timeout_ms);
    if (ready_line_.empty()) {
      const bool exited = !child_.Running();
      child_.Stop(SIGKILL);
      throw std::runtime_error(exited ? "canalsim serve exited before its ready line: " +
                                            child_.output()
                                      : "canalsim serve printed no ready line in time");
    }
    port_ = std::stoi(ready_line_.substr(ready_line_.find(key) + key.size()));
  }

  int port() const { return port_; }
  const std::string& ready_line() const { return ready_line_; }

  /// Sends `signal` (SIGTERM by default), then waits at most 20 s (SIGKILL after that).
  /// Returns the exit code, or 128 + signal if it was killed by one.
  int Stop(int signal = SIGTERM) { return child_.Stop(signal, 20000); }

 private:
  static ChildOptions Options(const std::vector<std::string>& args,
                              const std::filesystem::path& stderr_path) {
    ChildOptions o;
    o.argv = {CanalsimProgram(), "serve", "--listen", "127.0.0.1:0"};
    o.argv.insert(o.argv.end(), args.begin(), args.end());
    o.stderr_path = stderr_path;
    return o;
  }

  ChildProcess child_;
  int port_ = 0;
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
    std::vector<std::uint16_t> r(static_cast<std::size_t>(n), 0);
    const int rc = modbus_read_input_registers(ctx_, address, n, r.data());
    EXPECT_EQ(rc, n) << "read input " << address << ": " << modbus_strerror(errno);
    return r;
  }
  std::uint16_t Input(int address) { return Inputs(address, 1)[0]; }
  std::vector<std::uint16_t> Holdings(int address, int n) {
    std::vector<std::uint16_t> r(static_cast<std::size_t>(n), 0);
    const int rc = modbus_read_registers(ctx_, address, n, r.data());
    EXPECT_EQ(rc, n) << "read holding " << address << ": " << modbus_strerror(errno);
    return r;
  }
  std::uint16_t Holding(int address) { return Holdings(address, 1)[0]; }
  /// The float32 of holding registers address, address + 1, high word first ("abcd"), decoded
  /// here with memcpy, not with canalid's register codec.
  float HoldingFloatAbcd(int address) {
    const std::vector<std::uint16_t> r = Holdings(address, 2);
    const std::uint32_t bits = (static_cast<std::uint32_t>(r[0]) << 16) | r[1];
    float value = 0.0F;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
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
    std::vector<std::uint16_t> r(static_cast<std::size_t>(n), 0);
    return modbus_read_input_registers(ctx_, address, n, r.data()) == n ? 0 : errno;
  }
  modbus_t* ctx() { return ctx_; }

 private:
  modbus_t* ctx_ = nullptr;
};

}  // namespace canalid::testing
