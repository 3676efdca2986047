// The libmodbus RTU adapter against an independent RTU server (tests/drivers/
// modbus_rtu_pty_server.py, written from the serial-line spec) on a pseudo-terminal.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/plc_poller.h"
#include "tests/support/child_process.h"

namespace canalid::drivers {
namespace {

using enum RegisterKind;

constexpr int kUnit = 17;

/// The server child: stdin a pipe held open (it exits when stdin closes), stdout read for the
/// ready line, the pty's path.
class PtyServer {
 public:
  /// Reads the ready line (the device path), waiting at most 30 s.
  std::optional<std::string> Start() {
    canalid::testing::ChildOptions options;
    options.argv = {"/usr/bin/python3",
                    std::string(CANALID_SOURCE_DIR) + "/tests/drivers/modbus_rtu_pty_server.py",
                    std::to_string(kUnit)};
    options.stdin_pipe = true;
    child_ = std::make_unique<canalid::testing::ChildProcess>(options);
    const std::string line = child_->WaitForLine("/dev/", 30000);
    if (line.empty()) return std::nullopt;
    return line;
  }

 private:
  std::unique_ptr<canalid::testing::ChildProcess> child_;
};

ModbusRtuConfig Rtu(const std::string& device, int unit) {
  ModbusRtuConfig c;
  c.device = device;
  c.baud = 115200;
  c.parity = 'N';
  c.unit_id = unit;
  c.response_timeout_s = 0.5;
  return c;
}

TEST(ModbusRtu, ReadsWritesAndExceptionsOverAPty) {
  PtyServer server;
  const std::optional<std::string> device = server.Start();
  ASSERT_TRUE(device.has_value()) << "RTU pty server did not start";
  ModbusPort plc(Rtu(*device, kUnit));
  ASSERT_TRUE(plc.Connect().ok());
  std::array<uint16_t, 125> regs{};
  ASSERT_TRUE(plc.ReadRegisters(kHolding, 0, std::span(regs).first(100)).ok());
  for (int i = 0; i < 100; ++i) EXPECT_EQ(regs[static_cast<std::size_t>(i)], 3 * i) << i;
  ASSERT_TRUE(plc.ReadRegisters(kInput, 90, std::span(regs).first(10)).ok());
  EXPECT_EQ(regs[0], 1090);
  EXPECT_EQ(regs[9], 1099);

  const std::array<uint16_t, 2> pair = {0x3F80, 0x0000};
  ASSERT_TRUE(plc.WriteRegister(50, 4242).ok());
  ASSERT_TRUE(plc.WriteRegisters(51, pair).ok());
  ASSERT_TRUE(plc.ReadRegisters(kHolding, 50, std::span(regs).first(3)).ok());
  EXPECT_EQ(regs[0], 4242);
  EXPECT_EQ(regs[1], 0x3F80);
  EXPECT_EQ(regs[2], 0x0000);

  const PlcStatus exception = plc.ReadRegisters(kHolding, 95, std::span(regs).first(10));
  EXPECT_EQ(exception.kind, PlcErrorKind::kException);
  EXPECT_EQ(exception.exception_code, 2);
  // The link survives an exception reply.
  EXPECT_TRUE(plc.ReadRegisters(kHolding, 0, std::span(regs).first(1)).ok());
}

TEST(ModbusRtu, AnotherUnitIdGetsNoAnswerSoTimesOut) {
  PtyServer server;
  const std::optional<std::string> device = server.Start();
  ASSERT_TRUE(device.has_value());
  ModbusRtuConfig config = Rtu(*device, kUnit + 1);
  config.response_timeout_s = 0.05;
  ModbusPort plc(config);
  ASSERT_TRUE(plc.Connect().ok());
  std::array<uint16_t, 4> regs{};
  EXPECT_EQ(plc.ReadRegisters(kHolding, 0, regs).kind, PlcErrorKind::kTimeout);
}

TEST(ModbusRtu, PollerDecodesOverRtu) {
  PtyServer server;
  const std::optional<std::string> device = server.Start();
  ASSERT_TRUE(device.has_value());
  PollerConfig config;
  config.plc_name = "rtu";
  config.period_s = 1.0;
  PollChannel level;
  level.name = "level_m";
  level.address = 7;  // 21 counts
  level.scaling.scale = 0.01;
  PollChannel flow;
  flow.name = "flow_m3s";
  flow.kind = kInput;
  flow.address = 3;  // 1003 counts
  flow.scaling.scale = 0.001;
  config.channels = {level, flow};
  std::mutex mutex;
  std::condition_variable cv;
  std::optional<PollSample> sample;
  PlcPoller* poller_ptr = nullptr;
  PlcPoller poller(config, std::make_unique<ModbusPort>(Rtu(*device, kUnit)), [&] {
    std::lock_guard lock(mutex);
    cv.notify_all();
  });
  poller_ptr = &poller;
  poller.Start();
  std::unique_lock lock(mutex);
  // Bounded wait for the first poll; the predicate drains on this (consumer) thread.
  ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(30), [&] {
    poller_ptr->DrainSamples([&](const PollSample& s) { sample = s; });
    return sample.has_value();
  }));
  lock.unlock();
  poller.Stop();
  EXPECT_TRUE(sample->status.ok());
  EXPECT_DOUBLE_EQ(sample->values[0], 0.21);
  EXPECT_DOUBLE_EQ(sample->values[1], 1.003);
}

}  // namespace
}  // namespace canalid::drivers
