// ModbusPort and the poller against a Modbus TCP slave written here, on a loopback socket, that
// answers each request correctly except for one field chosen by the test: every such reply is
// refused with the field named and counted, the link stays usable, and libmodbus's own read path
// (which canalid no longer uses over TCP) is shown to accept the same replies.
#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "tests/support/notify_waiter.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::drivers {
namespace {

/// What the slave changes in one reply.
enum class Mutation {
  kNone,
  kTransactionId,    // transaction id + 1
  kProtocolId,       // protocol id 0x0001
  kUnitId,           // unit id + 1
  kLengthShort,      // MBAP length one less than the bytes sent
  kLengthLong,       // MBAP length one more than the bytes sent
  kLengthHuge,       // MBAP length 300
  kFunction,         // function 4 for 3
  kByteCount,        // one register fewer, byte count and length to match
  kEcho,             // a write reply echoing value + 1
  kException,        // exception 2 instead of the reply
  kConstantUnitOne,  // every reply says unit 1 (a gateway behind another unit id)
  kLate,             // the right reply, held back until the next request has come (so after
                     // the master's response timeout), then sent just before that one's reply
};

/// A one-connection Modbus TCP slave on a loopback port: holding and input register i reads
/// as 1000 + i, writes are echoed. Mutations queued by the test apply to the next replies in
/// order. Runs on its own thread until destroyed; every wait in it is bounded.
class HostileSlave {
 public:
  HostileSlave() {
    listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
    if (listen_fd_ < 0) throw std::runtime_error("hostile slave: no socket");
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
        listen(listen_fd_, 4) != 0) {
      close(listen_fd_);
      throw std::runtime_error("hostile slave: cannot listen on loopback");
    }
    socklen_t len = sizeof addr;
    getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { Serve(); });
  }
  ~HostileSlave() {
    stop_ = true;
    thread_.join();
    close(listen_fd_);
  }
  HostileSlave(const HostileSlave&) = delete;
  HostileSlave& operator=(const HostileSlave&) = delete;

  int port() const { return port_; }
  void Queue(Mutation m) {
    std::lock_guard lock(mutex_);
    queue_.push_back(m);
  }
  void Always(Mutation m) { always_ = m; }

 private:
  // Waits up to 50 ms for `fd`; false when stopping.
  bool Ready(int fd) const {
    while (!stop_) {
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 50) > 0) return true;
    }
    return false;
  }
  bool ReadExactly(int fd, uint8_t* out, std::size_t n) const {
    std::size_t got = 0;
    while (got < n) {
      if (!Ready(fd)) return false;
      const ssize_t r = recv(fd, out + got, n - got, 0);
      if (r <= 0) return false;
      got += static_cast<std::size_t>(r);
    }
    return true;
  }
  Mutation Next() {
    std::lock_guard lock(mutex_);
    if (queue_.empty()) return always_;
    const Mutation m = queue_.front();
    queue_.pop_front();
    return m;
  }

  void Serve() {
    while (!stop_) {
      if (!Ready(listen_fd_)) return;
      const int fd = accept(listen_fd_, nullptr, nullptr);
      if (fd < 0) continue;
      std::array<uint8_t, 300> request{};
      std::vector<uint8_t> held;  // a kLate reply, sent just before the next one
      while (ReadExactly(fd, request.data(), 7)) {
        const std::size_t pdu = (static_cast<std::size_t>(request[4]) << 8 | request[5]) - 1;
        if (pdu < 1 || pdu > 253 || !ReadExactly(fd, request.data() + 7, pdu)) break;
        const Mutation m = Next();
        std::vector<uint8_t> reply = Reply(request.data(), m);
        if (m == Mutation::kLate) {
          held = std::move(reply);  // the master times out, then asks again
          continue;
        }
        held.insert(held.end(), reply.begin(), reply.end());
        if (send(fd, held.data(), held.size(), MSG_NOSIGNAL) < 0) break;
        held.clear();
      }
      close(fd);
    }
  }

  static std::vector<uint8_t> Reply(const uint8_t* req, Mutation m) {
    const uint8_t function = req[7];
    std::vector<uint8_t> pdu;
    if (m == Mutation::kException) {
      pdu = {static_cast<uint8_t>(function | 0x80), 0x02};
    } else if (function == 3 || function == 4) {
      const int address = req[8] << 8 | req[9];
      int count = req[10] << 8 | req[11];
      if (m == Mutation::kByteCount) --count;
      pdu = {m == Mutation::kFunction ? uint8_t{4} : function, static_cast<uint8_t>(2 * count)};
      for (int i = 0; i < count; ++i) {
        const int value = 1000 + address + i;
        pdu.push_back(static_cast<uint8_t>(value >> 8));
        pdu.push_back(static_cast<uint8_t>(value & 0xff));
      }
    } else {
      pdu.assign(req + 7, req + 7 + 5);  // function, address and value (6) or count (16)
      if (m == Mutation::kEcho) ++pdu[4];
    }
    std::size_t length = pdu.size() + 1;
    if (m == Mutation::kLengthShort) --length;
    if (m == Mutation::kLengthLong) ++length;
    if (m == Mutation::kLengthHuge) length = 300;
    std::vector<uint8_t> adu = {req[0],
                                req[1],
                                0,
                                0,
                                static_cast<uint8_t>(length >> 8),
                                static_cast<uint8_t>(length & 0xff),
                                req[6]};
    if (m == Mutation::kTransactionId) adu[1] = static_cast<uint8_t>(adu[1] + 1);
    if (m == Mutation::kProtocolId) adu[3] = 1;
    if (m == Mutation::kUnitId) adu[6] = static_cast<uint8_t>(adu[6] + 1);
    if (m == Mutation::kConstantUnitOne) adu[6] = 1;
    adu.insert(adu.end(), pdu.begin(), pdu.end());
    return adu;
  }

  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<Mutation> always_{Mutation::kNone};
  std::mutex mutex_;
  std::deque<Mutation> queue_;
  std::thread thread_;
};

ModbusTcpConfig Config(int port, int unit_id = 7) {
  ModbusTcpConfig c;
  c.port = port;
  c.unit_id = unit_id;
  c.response_timeout_s = 0.3;
  c.connect_timeout_s = 1.0;
  return c;
}

::testing::AssertionResult ReadsCleanly(ModbusPort& plc) {
  std::array<uint16_t, 3> regs{};
  const PlcStatus s = plc.ReadRegisters(RegisterKind::kHolding, 20, regs);
  if (!s.ok()) {
    return ::testing::AssertionFailure() << "clean read failed: " << PlcErrorKindName(s.kind) << " "
                                         << ReplyFaultName(s.reply_fault);
  }
  if (regs != std::array<uint16_t, 3>{1020, 1021, 1022}) {
    return ::testing::AssertionFailure()
           << "clean read returned " << regs[0] << " " << regs[1] << " " << regs[2];
  }
  return ::testing::AssertionSuccess();
}

struct Case {
  Mutation mutation;
  PlcErrorKind kind;
  ReplyFault fault;
  bool keeps_link;  // false: the frame could not be delimited, so the port dropped the link
};

TEST(ModbusReplyFaults, EachWrongFieldIsRefusedAndNamed) {
  HostileSlave slave;
  ModbusPort plc(Config(slave.port()));
  ASSERT_TRUE(plc.Connect().ok());
  ASSERT_TRUE(ReadsCleanly(plc));
  using enum Mutation;
  using K = PlcErrorKind;
  const Case cases[] = {
      // The id of a request not yet sent: no late reply, so refused (the frame was whole).
      {kTransactionId, K::kBadData, ReplyFault::kTransactionId, true},
      {kProtocolId, K::kDisconnected, ReplyFault::kProtocolId, false},
      {kUnitId, K::kBadData, ReplyFault::kUnitId, true},
      // The MBAP length one short: the PDU does not fit its function, so the framing is lost.
      {kLengthShort, K::kDisconnected, ReplyFault::kLength, false},
      {kLengthLong, K::kDisconnected, ReplyFault::kTruncated, false},
      {kLengthHuge, K::kDisconnected, ReplyFault::kLength, false},
      {kFunction, K::kBadData, ReplyFault::kFunction, true},
      {kByteCount, K::kBadData, ReplyFault::kByteCount, true},
      {kException, K::kException, ReplyFault::kNone, true},
  };
  for (const Case& c : cases) {
    const int m = static_cast<int>(c.mutation);
    slave.Queue(c.mutation);
    std::array<uint16_t, 3> regs{};
    const PlcStatus s = plc.ReadRegisters(RegisterKind::kHolding, 20, regs);
    EXPECT_EQ(s.kind, c.kind) << "mutation " << m;
    EXPECT_EQ(s.reply_fault, c.fault) << "mutation " << m;
    EXPECT_EQ(plc.connected(), c.keeps_link) << "mutation " << m;
    if (!plc.connected()) {
      ASSERT_TRUE(plc.Connect().ok()) << "mutation " << m;
    }
    EXPECT_TRUE(ReadsCleanly(plc)) << "after mutation " << m;
  }
  slave.Queue(kEcho);
  const PlcStatus echo = plc.WriteRegister(5, 42);
  EXPECT_EQ(echo.kind, K::kBadData);
  EXPECT_EQ(echo.reply_fault, ReplyFault::kEcho);
  slave.Queue(kEcho);
  const std::array<uint16_t, 2> pair = {1, 2};
  EXPECT_EQ(plc.WriteRegisters(5, pair).reply_fault, ReplyFault::kEcho);
  slave.Queue(kUnitId);
  EXPECT_EQ(plc.WriteRegister(5, 42).reply_fault, ReplyFault::kUnitId);
  EXPECT_TRUE(plc.WriteRegister(5, 42).ok());
  EXPECT_TRUE(ReadsCleanly(plc));
}

// A reply that comes after its request timed out is skipped by its transaction id when the next
// request's reply follows it, so one late reply does not put every later read one reply behind.
// The slave holds the late reply until the second request has come: no timing is involved.
TEST(ModbusReplyFaults, ALateReplyIsSkippedAndTheNextReadIsAnswered) {
  HostileSlave slave;
  ModbusPort plc(Config(slave.port()));
  ASSERT_TRUE(plc.Connect().ok());
  slave.Queue(Mutation::kLate);
  std::array<uint16_t, 3> regs{};
  const PlcStatus late = plc.ReadRegisters(RegisterKind::kHolding, 20, regs);
  EXPECT_EQ(late.kind, PlcErrorKind::kTimeout);
  EXPECT_EQ(late.reply_fault, ReplyFault::kNone);
  ASSERT_TRUE(plc.connected());
  const PlcStatus next = plc.ReadRegisters(RegisterKind::kHolding, 20, regs);
  EXPECT_TRUE(next.ok()) << PlcErrorKindName(next.kind);
  EXPECT_EQ(next.reply_fault, ReplyFault::kTransactionId) << "the skipped late reply is counted";
  EXPECT_EQ(regs, (std::array<uint16_t, 3>{1020, 1021, 1022}));
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(ReadsCleanly(plc)) << i;
}

// Why canalid frames TCP itself: libmodbus 3.1.6's read takes these replies as good data. If a
// later libmodbus refuses them, this test says so and the reason in modbus_port.h can be revised.
TEST(ModbusReplyFaults, LibmodbusAloneAcceptsAWrongUnitProtocolAndLength) {
  HostileSlave slave;
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", slave.port());
  ASSERT_NE(ctx, nullptr);
  ASSERT_EQ(modbus_set_slave(ctx, 7), 0);
  modbus_set_response_timeout(ctx, 0, 300000);
  ASSERT_EQ(modbus_connect(ctx), 0);
  for (const Mutation m : {Mutation::kUnitId, Mutation::kProtocolId, Mutation::kLengthShort}) {
    slave.Queue(m);
    std::array<uint16_t, 3> regs{};
    EXPECT_EQ(modbus_read_registers(ctx, 20, 3, regs.data()), 3)
        << "libmodbus refused mutation " << static_cast<int>(m);
    modbus_flush(ctx);
  }
  modbus_close(ctx);
  modbus_free(ctx);
}

TEST(ModbusReplyFaults, ThePollerCountsAReplyFaultByItsField) {
  HostileSlave slave;
  PollerConfig config;
  config.plc_name = "hostile";
  config.period_s = 2.0;  // waits end on events, so the period costs no test time
  PollChannel level;
  level.name = "level";
  level.kind = RegisterKind::kHolding;
  level.address = 20;
  config.channels = {level};
  canalid::testing::NotifyWaiter waiter;
  slave.Always(Mutation::kConstantUnitOne);
  PlcPoller poller(config, std::make_unique<ModbusPort>(Config(slave.port(), 7)),
                   waiter.Callback());
  poller.Start();
  std::optional<PollSample> sample;
  ASSERT_TRUE(waiter.Until([&] {
    poller.DrainSamples([&](const PollSample& s) { sample = s; });
    return sample.has_value();
  }));
  poller.Stop();
  EXPECT_EQ(sample->status.kind, PlcErrorKind::kBadData);
  EXPECT_EQ(sample->status.reply_fault, ReplyFault::kUnitId);
  EXPECT_FALSE(sample->valid(0)) << "a reply from another unit is never data";
  const PollerCounters c = poller.counters();
  EXPECT_GE(c.reply_faults[static_cast<int>(ReplyFault::kUnitId)], 1);
  EXPECT_EQ(c.reply_faults[static_cast<int>(ReplyFault::kUnitId)],
            c.read_errors[static_cast<int>(PlcErrorKind::kBadData)]);
  EXPECT_EQ(c.block_reads_ok, 0);
}

}  // namespace
}  // namespace canalid::drivers
