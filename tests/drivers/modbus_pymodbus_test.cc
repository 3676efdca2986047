// The libmodbus adapter and the poller against an independent Modbus TCP server: pymodbus 3.0
// from Debian, run by /usr/bin/python3 (the PATH python3 may lack Debian's packages) as a child
// process on a free loopback port, stopped by its pid.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "tests/support/child_process.h"
#include "tests/support/loopback_port.h"
#include "tests/support/notify_waiter.h"

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::drivers {
namespace {

using enum RegisterKind;

const char* const kPython = "/usr/bin/python3";

using canalid::testing::AcceptsOnLoopback;
using canalid::testing::FreeLoopbackPort;

/// The pymodbus server child process.
class PymodbusServer {
 public:
  explicit PymodbusServer(int port) : port_(port) {}

  /// Starts the server and waits until its port accepts a connection: a bounded wait (30 s) that
  /// re-checks whenever the child prints, every 20 ms, and ends at once if the child exits.
  ::testing::AssertionResult Start() {
    const auto dir = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / "modbus_pymodbus";
    std::filesystem::create_directories(dir);
    canalid::testing::ChildOptions options;
    options.argv = {kPython,
                    std::string(CANALID_SOURCE_DIR) + "/tests/drivers/modbus_test_server.py",
                    std::to_string(port_)};
    options.stderr_path = dir / ("server-" + std::to_string(port_) + ".log");
    child_ = std::make_unique<canalid::testing::ChildProcess>(options);
    if (child_->WaitUntil([&] { return AcceptsOnLoopback(port_); }, 30000)) {
      return ::testing::AssertionSuccess();
    }
    if (!child_->Running()) {
      return ::testing::AssertionFailure()
             << "pymodbus server exited early, see " << options.stderr_path;
    }
    return ::testing::AssertionFailure() << "pymodbus server not accepting within 30 s";
  }

  /// SIGKILL: the server vanishes as a crashed PLC would.
  void Kill() {
    if (child_) child_->Stop(SIGKILL);
  }

 private:
  int port_;
  std::unique_ptr<canalid::testing::ChildProcess> child_;
};

using Waiter = canalid::testing::NotifyWaiter;

ModbusTcpConfig TcpConfig(int port) {
  ModbusTcpConfig c;
  c.port = port;
  c.response_timeout_s = 1.0;
  c.connect_timeout_s = 1.0;
  return c;
}

PollChannel Channel(RegisterKind kind, int address, drivers::RegisterType type,
                    core::WordOrder order, double scale) {
  PollChannel c;
  c.name = "ch" + std::to_string(address);
  c.kind = kind;
  c.address = address;
  c.scaling.type = type;
  c.scaling.word_order = order;
  c.scaling.scale = scale;
  return c;
}

PollerConfig ServerMapConfig() {
  using enum drivers::RegisterType;
  using enum core::WordOrder;
  PollerConfig c;
  c.plc_name = "pymodbus";
  c.period_s = 2.0;  // > response timeout; waits end on events, so this costs no test time
  c.backoff_initial_s = 0.05;
  c.backoff_max_s = 0.4;
  c.channels = {Channel(kHolding, 0, kU16, kHighWordFirst, 0.001),
                Channel(kHolding, 1, kF32, kHighWordFirst, 1.0),
                Channel(kHolding, 3, kI32, kLowWordFirst, 1.0),
                Channel(kHolding, 5, kI16, kHighWordFirst, 1.0),
                Channel(kInput, 0, kF32, kHighWordFirst, 1.0)};
  return c;
}

TEST(ModbusPymodbus, PortReadsWritesAndTypesExceptions) {
  const int port = FreeLoopbackPort();
  ASSERT_GT(port, 0) << "no free loopback port";
  PymodbusServer server(port);
  ASSERT_TRUE(server.Start());
  ModbusPort plc(TcpConfig(port));
  ASSERT_TRUE(plc.Connect().ok());
  std::array<uint16_t, 6> regs{};
  ASSERT_TRUE(plc.ReadRegisters(kHolding, 0, regs).ok());
  EXPECT_EQ(regs[0], 1234);
  EXPECT_EQ(regs[1], 0x4050);  // 3.25f = 0x40500000
  EXPECT_EQ(regs[5], 0xFFD6);  // -42

  const std::array<uint16_t, 2> pair = {0xBEEF, 0x0102};
  ASSERT_TRUE(plc.WriteRegister(10, 777).ok());
  ASSERT_TRUE(plc.WriteRegisters(11, pair).ok());
  std::array<uint16_t, 3> back{};
  ASSERT_TRUE(plc.ReadRegisters(kHolding, 10, back).ok());
  EXPECT_EQ(back[0], 777);
  EXPECT_EQ(back[1], 0xBEEF);
  EXPECT_EQ(back[2], 0x0102);

  std::array<uint16_t, 4> beyond{};
  const PlcStatus exception = plc.ReadRegisters(kHolding, 150, beyond);
  EXPECT_EQ(exception.kind, PlcErrorKind::kException);
  EXPECT_EQ(exception.exception_code, 2) << "illegal data address";
  EXPECT_TRUE(plc.connected()) << "an exception reply keeps the link";

  std::array<uint16_t, 126> too_many{};
  EXPECT_EQ(plc.ReadRegisters(kHolding, 0, too_many).kind, PlcErrorKind::kConfig);
  ASSERT_TRUE(plc.ReadRegisters(kInput, 0, std::span(regs).first(2)).ok());
  EXPECT_EQ(regs[0], 0xBF00);  // -0.5f = 0xBF000000
}

TEST(ModbusPymodbus, RefusedConnectIsDisconnected) {
  ModbusPort plc(TcpConfig(FreeLoopbackPort()));
  const PlcStatus s = plc.Connect();
  EXPECT_EQ(s.kind, PlcErrorKind::kDisconnected);
  std::array<uint16_t, 1> r{};
  EXPECT_EQ(plc.ReadRegisters(kHolding, 0, r).kind, PlcErrorKind::kDisconnected);
}

// A peer whose kernel completes the TCP handshake (listen backlog) but never answers.
TEST(ModbusPymodbus, SilentPeerIsATimeoutAndConnectionsToNowhereAreDisconnected) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  ASSERT_EQ(listen(fd, 4), 0);
  ModbusTcpConfig config = TcpConfig(ntohs(addr.sin_port));
  config.response_timeout_s = 0.05;
  ModbusPort plc(config);
  ASSERT_TRUE(plc.Connect().ok());
  std::array<uint16_t, 10> regs{};
  const PlcStatus s = plc.ReadRegisters(kHolding, 0, regs);
  EXPECT_EQ(s.kind, PlcErrorKind::kTimeout);
  EXPECT_TRUE(plc.connected()) << "a timeout alone keeps the link; the poller decides";
  close(fd);

  ModbusRtuConfig rtu;
  rtu.device = "/nonexistent/ttyCANALID";
  ModbusPort serial(rtu);
  EXPECT_EQ(serial.Connect().kind, PlcErrorKind::kDisconnected);
}

TEST(ModbusPymodbus, ConfigValidationNamesTheField) {
  ModbusTcpConfig tcp;
  tcp.port = 0;
  try {
    ModbusPort bad(tcp);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("port"), std::string::npos) << e.what();
  }
  ModbusRtuConfig rtu;
  rtu.device = "/dev/ttyUSB0";
  rtu.parity = 'X';
  EXPECT_THROW(ModbusPort{rtu}, std::invalid_argument);
  rtu.parity = 'N';
  rtu.unit_id = 0;  // broadcast: no replies, so no reads
  EXPECT_THROW(ModbusPort{rtu}, std::invalid_argument);
  tcp = ModbusTcpConfig{};
  tcp.response_timeout_s = 0.0;
  EXPECT_THROW(ModbusPort{tcp}, std::invalid_argument);
}

TEST(ModbusPymodbus, PollerDecodesTheServerMapAndTypesExceptionBlocks) {
  const int port = FreeLoopbackPort();
  ASSERT_GT(port, 0) << "no free loopback port";
  PymodbusServer server(port);
  ASSERT_TRUE(server.Start());
  PollerConfig config = ServerMapConfig();
  config.channels.push_back(
      Channel(kHolding, 150, drivers::RegisterType::kU16, core::WordOrder::kHighWordFirst, 1.0));
  Waiter waiter;
  PlcPoller poller(config, std::make_unique<ModbusPort>(TcpConfig(port)), waiter.Callback());
  ASSERT_EQ(poller.plan().blocks.size(), 3u);
  poller.Start();
  std::optional<PollSample> sample;
  ASSERT_TRUE(waiter.Until([&] {
    poller.DrainSamples([&](const PollSample& s) { sample = s; });
    return sample.has_value();
  }));
  // Values the server computed with Python's struct module.
  EXPECT_DOUBLE_EQ(sample->values[0], 1.234);
  EXPECT_DOUBLE_EQ(sample->values[1], 3.25);
  EXPECT_DOUBLE_EQ(sample->values[2], -123456.0);
  EXPECT_DOUBLE_EQ(sample->values[3], -42.0);
  EXPECT_DOUBLE_EQ(sample->values[4], -0.5);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_TRUE(sample->valid(i)) << i;
  EXPECT_EQ(sample->quality[5], SampleQuality::kReadFailed);
  EXPECT_EQ(sample->status.kind, PlcErrorKind::kException);
  EXPECT_EQ(sample->status.exception_code, 2);
  const PollerCounters c = poller.counters();
  EXPECT_EQ(c.read_errors[static_cast<int>(PlcErrorKind::kException)], 1);
  EXPECT_GT(c.last_round_trip_s, 0.0);
}

TEST(ModbusPymodbus, KilledServerIsDisconnectedThenReconnectedWithBackoff) {
  const int port = FreeLoopbackPort();
  ASSERT_GT(port, 0) << "no free loopback port";
  PymodbusServer server(port);
  ASSERT_TRUE(server.Start());
  PollerConfig config = ServerMapConfig();
  config.period_s = 1.1;
  Waiter waiter;
  PlcPoller poller(config, std::make_unique<ModbusPort>(TcpConfig(port)), waiter.Callback());
  poller.Start();
  std::optional<PollSample> last;
  auto drain = [&] { poller.DrainSamples([&](const PollSample& s) { last = s; }); };
  ASSERT_TRUE(waiter.Until([&] {
    drain();
    return last && last->status.ok();
  }));

  server.Kill();
  ASSERT_TRUE(waiter.Until([&] {
    drain();
    return last->status.kind == PlcErrorKind::kDisconnected;
  }));
  // Refused reconnects back off 0.05 s, 0.1 s, 0.2 s ...
  ASSERT_TRUE(waiter.Until([&] { return poller.counters().connect_failures >= 3; }));
  PollerCounters c = poller.counters();
  EXPECT_FALSE(c.connected);
  EXPECT_GE(c.current_backoff_s, 0.2);
  EXPECT_LE(c.current_backoff_s, 0.4);
  EXPECT_EQ(c.reconnects, 0);

  PymodbusServer again(port);
  ASSERT_TRUE(again.Start());
  ASSERT_TRUE(waiter.Until([&] { return poller.counters().reconnects == 1; }));
  ASSERT_TRUE(waiter.Until([&] {
    drain();
    return last->status.ok();
  }));
  EXPECT_DOUBLE_EQ(last->values[1], 3.25);
  c = poller.counters();
  EXPECT_TRUE(c.connected);
  EXPECT_EQ(c.current_backoff_s, 0.0);
  EXPECT_GE(c.read_errors[static_cast<int>(PlcErrorKind::kDisconnected)], 1);
}

}  // namespace
}  // namespace canalid::drivers
