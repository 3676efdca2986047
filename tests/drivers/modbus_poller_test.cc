// The poller against the in-memory FakePlcPort: decoding, write whitelist, clamp and rate limit,
// typed errors, reconnect with backoff. The pymodbus suite repeats the I/O part over real TCP.
#include <gtest/gtest.h>

#include "tests/support/notify_waiter.h"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "drivers/modbus/fake_plc_port.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::drivers {
namespace {

using enum RegisterKind;

/// Wakes the test thread on each poller notification; waits are bounded (20 s) but end on the
/// event, never on elapsed time.
using Waiter = canalid::testing::NotifyWaiter;

PollChannel Channel(const char* name, RegisterKind kind, int address, drivers::RegisterType type,
                    double scale) {
  PollChannel c;
  c.name = name;
  c.kind = kind;
  c.address = address;
  c.scaling.type = type;
  c.scaling.scale = scale;
  return c;
}

struct Rig {
  FakePlcPort* fake = nullptr;
  Waiter waiter;
  std::unique_ptr<PlcPoller> poller;

  void Make(PollerConfig config) {
    auto port = std::make_unique<FakePlcPort>();
    fake = port.get();
    poller = std::make_unique<PlcPoller>(std::move(config), std::move(port), waiter.Callback());
  }
  /// The next poll with sequence >= `after` (drains older ones).
  std::optional<PollSample> NextSample(int64_t after) {
    std::optional<PollSample> found;
    waiter.Until([&] {
      poller->DrainSamples([&](const PollSample& s) {
        if (!found && s.sequence >= after) found = s;
      });
      return found.has_value();
    });
    return found;
  }
  std::optional<WriteResult> Result(uint64_t id) {
    std::optional<WriteResult> found;
    waiter.Until([&] {
      poller->DrainWriteResults([&](const WriteResult& r) {
        if (r.id == id) found = r;
      });
      return found.has_value();
    });
    return found;
  }
};

PollerConfig BaseConfig() {
  PollerConfig c;
  c.plc_name = "fake";
  c.period_s = 0.005;
  c.backoff_initial_s = 0.001;
  c.backoff_max_s = 0.004;
  c.channels.push_back(Channel("level_m", kHolding, 0, drivers::RegisterType::kU16, 0.001));
  c.channels.push_back(Channel("flow_m3s", kInput, 10, drivers::RegisterType::kF32, 1.0));
  PollChannel gate = Channel("gate_m", kHolding, 4, drivers::RegisterType::kU16, 0.001);
  gate.writable = true;
  gate.limits = {0.0, 1.5, std::numeric_limits<double>::infinity()};
  c.channels.push_back(gate);
  PollChannel slow = Channel("slow_gate_m", kHolding, 6, drivers::RegisterType::kU16, 0.001);
  slow.writable = true;
  slow.limits = {0.0, 1.5, 1e-6};  // 1 um/s: any test run moves it by far less than a count
  slow.scaling.max_value = 1.5;
  c.channels.push_back(slow);
  return c;
}

TEST(ModbusPoller, DecodesEveryChannelOfAPoll) {
  Rig rig;
  rig.Make(BaseConfig());
  ASSERT_EQ(rig.poller->plan().blocks.size(), 2u);  // holding 0..6 and input 10..11
  rig.fake->SetRegister(kHolding, 0, 1234);
  rig.fake->SetRegister(kInput, 10, 0x4049);  // 3.140625f = 0x40490000
  rig.fake->SetRegister(kInput, 11, 0x0000);
  rig.fake->SetRegister(kHolding, 4, 500);
  rig.poller->Start();
  const auto s = rig.NextSample(0);
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE(s->status.ok());
  ASSERT_EQ(s->values.size(), 4u);
  EXPECT_DOUBLE_EQ(s->values[0], 1.234);
  EXPECT_DOUBLE_EQ(s->values[1], 3.140625);
  EXPECT_DOUBLE_EQ(s->values[2], 0.5);
  EXPECT_EQ(s->raw[1][0], 0x4049);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(s->valid(i)) << i;
  EXPECT_GT(rig.poller->counters().polls, 0);
  EXPECT_TRUE(rig.poller->counters().connected);
}

TEST(ModbusPoller, WritesOnlyWhitelistedChannelsClampedAndRateLimited) {
  Rig rig;
  rig.Make(BaseConfig());
  rig.fake->SetRegister(kHolding, 4, 500);
  rig.fake->SetRegister(kHolding, 6, 200);
  rig.poller->Start();
  ASSERT_TRUE(rig.NextSample(0).has_value());  // the limiters now have their reference

  EXPECT_EQ(rig.poller->RequestWrite(0, 1.0).status, WriteQueueStatus::kNotWritable);
  EXPECT_EQ(rig.poller->RequestWrite(9, 1.0).status, WriteQueueStatus::kUnknownChannel);

  const WriteTicket clamp = rig.poller->RequestWrite(2, 2.0);
  ASSERT_EQ(clamp.status, WriteQueueStatus::kQueued);
  const auto clamped = rig.Result(clamp.id);
  ASSERT_TRUE(clamped.has_value());
  EXPECT_EQ(clamped->outcome, WriteOutcome::kWritten);
  EXPECT_TRUE(clamped->clamped);
  EXPECT_DOUBLE_EQ(clamped->written, 1.5);
  EXPECT_EQ(rig.fake->GetRegister(kHolding, 4), 1500);

  const WriteTicket slow = rig.poller->RequestWrite(3, 1.0);
  const auto limited = rig.Result(slow.id);
  ASSERT_TRUE(limited.has_value());
  EXPECT_EQ(limited->outcome, WriteOutcome::kWritten);
  EXPECT_TRUE(limited->rate_limited);
  // 0.2 m + 1e-6 m/s * (well under 1000 s of test) rounds back to 200 counts of 1 mm.
  EXPECT_LT(limited->written - 0.2, 1e-3);
  EXPECT_EQ(rig.fake->GetRegister(kHolding, 6), 200);

  const auto nan_result = rig.Result(rig.poller->RequestWrite(2, std::nan("")).id);
  ASSERT_TRUE(nan_result.has_value());
  EXPECT_EQ(nan_result->outcome, WriteOutcome::kNotFinite);
  EXPECT_EQ(rig.poller->counters().writes_ok, 2);
  EXPECT_EQ(rig.poller->counters().writes_failed, 1);
}

TEST(ModbusPoller, RateLimitRestartsFromAFreshReadingAfterAReconnect) {
  Rig rig;
  rig.Make(BaseConfig());
  rig.fake->SetRegister(kHolding, 6, 200);
  rig.poller->Start();
  ASSERT_TRUE(rig.NextSample(0).has_value());
  auto r = rig.Result(rig.poller->RequestWrite(3, 1.0).id);
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->written, 0.2, 1e-3);

  // The PLC restarts holding 0.9 m: the limiter must start from there, not from 0.2 m.
  rig.fake->FailNextRequest({PlcErrorKind::kDisconnected, 0, 104});
  rig.fake->SetRegister(kHolding, 6, 900);
  ASSERT_TRUE(rig.waiter.Until([&] { return rig.poller->counters().reconnects == 1; }));
  ASSERT_TRUE(rig.waiter.Until([&] {
    std::optional<PollSample> s = rig.NextSample(0);
    return s && s->valid(3) && std::abs(s->values[3] - 0.9) < 1e-9;
  }));
  r = rig.Result(rig.poller->RequestWrite(3, 1.0).id);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->outcome, WriteOutcome::kWritten);
  EXPECT_NEAR(r->written, 0.9, 1e-3);
  EXPECT_EQ(rig.fake->GetRegister(kHolding, 6), 900);
}

TEST(ModbusPoller, RefusesAWriteWithoutAValidReading) {
  PollerConfig config = BaseConfig();
  config.channels[3].scaling.max_value = 0.1;  // register 200 = 0.2 m: out of range, invalid
  Rig rig;
  rig.Make(config);
  rig.fake->SetRegister(kHolding, 6, 200);
  rig.poller->Start();
  const auto s = rig.NextSample(0);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->quality[3], SampleQuality::kOutOfRange);
  const auto r = rig.Result(rig.poller->RequestWrite(3, 0.05).id);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->outcome, WriteOutcome::kNoReference);
  EXPECT_EQ(rig.fake->writes(), 0);
}

TEST(ModbusPoller, ExceptionRepliesAreTypedAndInvalidateTheirBlockOnly) {
  Rig rig;
  rig.Make(BaseConfig());
  rig.fake->SetRegister(kInput, 10, 0x3F80);                    // 1.0f
  rig.fake->FailNextRequest({PlcErrorKind::kException, 2, 0});  // the holding block, read first
  rig.poller->Start();
  const auto s = rig.NextSample(0);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->status.kind, PlcErrorKind::kException);
  EXPECT_EQ(s->status.exception_code, 2);
  EXPECT_EQ(s->quality[0], SampleQuality::kReadFailed);
  EXPECT_EQ(s->quality[2], SampleQuality::kReadFailed);
  EXPECT_TRUE(s->valid(1));
  EXPECT_DOUBLE_EQ(s->values[1], 1.0);
  const PollerCounters c = rig.poller->counters();
  EXPECT_EQ(c.read_errors[static_cast<int>(PlcErrorKind::kException)], 1);
  EXPECT_EQ(c.reconnects, 0) << "an exception reply is not a link failure";
  const auto next = rig.NextSample(s->sequence + 1);
  ASSERT_TRUE(next.has_value());
  EXPECT_TRUE(next->status.ok());
}

TEST(ModbusPoller, ReconnectsWithBoundedExponentialBackoff) {
  Rig rig;
  rig.Make(BaseConfig());
  rig.poller->Start();
  ASSERT_TRUE(rig.NextSample(0).has_value());
  rig.fake->SetConnectResult({PlcErrorKind::kDisconnected, 0, 111});
  rig.fake->FailNextRequest({PlcErrorKind::kDisconnected, 0, 104});
  // Backoff 1 ms, 2 ms, 4 ms, 4 ms ...: after four failures the delay sits at the 4 ms bound.
  ASSERT_TRUE(rig.waiter.Until([&] { return rig.poller->counters().connect_failures >= 4; }));
  PollerCounters c = rig.poller->counters();
  EXPECT_FALSE(c.connected);
  EXPECT_DOUBLE_EQ(c.current_backoff_s, 0.004);
  EXPECT_EQ(c.read_errors[static_cast<int>(PlcErrorKind::kDisconnected)], 1);
  rig.fake->SetConnectResult(PlcStatus::Ok());
  ASSERT_TRUE(rig.waiter.Until([&] { return rig.poller->counters().reconnects == 1; }));
  const auto after = rig.NextSample(0);
  ASSERT_TRUE(after.has_value());
  EXPECT_TRUE(rig.waiter.Until([&] {
    std::optional<PollSample> s = rig.NextSample(0);
    return s && s->status.ok();
  }));
  c = rig.poller->counters();
  EXPECT_TRUE(c.connected);
  EXPECT_DOUBLE_EQ(c.current_backoff_s, 0.0);
}

TEST(ModbusPoller, ConsecutiveTimeoutsDropTheLink) {
  PollerConfig config = BaseConfig();
  config.channels.resize(1);  // one block, so one timeout per poll
  config.timeouts_before_reconnect = 3;
  Rig rig;
  rig.Make(config);
  for (int i = 0; i < 3; ++i) rig.fake->FailNextRequest({PlcErrorKind::kTimeout, 0, 110});
  rig.poller->Start();
  ASSERT_TRUE(rig.waiter.Until([&] { return rig.poller->counters().reconnects == 1; }));
  EXPECT_EQ(rig.poller->counters().read_errors[static_cast<int>(PlcErrorKind::kTimeout)], 3);
  EXPECT_EQ(rig.fake->connects(), 2);
}

TEST(ModbusPoller, AFullRingDropsPollsInsteadOfBlocking) {
  PollerConfig config = BaseConfig();
  config.sample_queue_capacity = 2;
  Rig rig;
  rig.Make(config);
  rig.poller->Start();
  ASSERT_TRUE(rig.waiter.Until([&] { return rig.poller->counters().samples_dropped >= 3; }));
  std::vector<int64_t> sequences;
  rig.poller->DrainSamples([&](const PollSample& s) { sequences.push_back(s.sequence); });
  ASSERT_GE(sequences.size(), 2u);
  EXPECT_EQ(sequences[0], 0);
  EXPECT_EQ(sequences[1], 1);
}

TEST(ModbusPoller, RejectsBadConfigs) {
  PollerConfig config = BaseConfig();
  config.channels[1].writable = true;  // an input register
  config.channels[1].limits = {0.0, 1.0, 1.0};
  EXPECT_THROW(PlcPoller(config, std::make_unique<FakePlcPort>(), {}), std::invalid_argument);
  config = BaseConfig();
  config.period_s = 0.0;
  EXPECT_THROW(PlcPoller(config, std::make_unique<FakePlcPort>(), {}), std::invalid_argument);
  config = BaseConfig();
  config.channels.clear();
  EXPECT_THROW(PlcPoller(config, std::make_unique<FakePlcPort>(), {}), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::drivers
