// LcmBus over liblcm's tcpq transport against tests/support/tcpq_test_hub.h (Debian's liblcm-bin
// ships no tcpq hub). The truths: losing the hub is a lost connection (Handle -1, Publish false),
// never liblcm's select() on fd -1 (an abort on main); Reconnect() subscribes again and messages
// flow; a 16 MB message on the command channel is refused by its size, and the next genuine command
// accepted.
#include <gtest/gtest.h>
#include <unistd.h>

#include <future>
#include <string>
#include <vector>

#include "drivers/auth/command_auth.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/lcm_bus.h"
#include "tests/support/tcpq_test_hub.h"

namespace canalid::drivers {
namespace {

using testing::kHubWaitMs;
using testing::TcpqTestHub;
constexpr int kWaitMs = kHubWaitMs;
using TestHub = TcpqTestHub;

// LcmBus's constructor (and Reconnect) connects and waits for the hub's answer: accept on
// another thread meanwhile.
struct Connected {
  std::unique_ptr<LcmBus> bus;
  int hub_side = -1;
};
Connected Connect(TestHub& hub) {
  auto accepted = std::async(std::launch::async, [&hub] { return hub.Accept(); });
  Connected c;
  c.bus = std::make_unique<LcmBus>(hub.url());
  c.hub_side = accepted.get();
  return c;
}

TEST(LcmTcpq, LosingTheHubIsALostConnectionAndReconnectSubscribesAgain) {
  TestHub hub;
  Connected c = Connect(hub);
  ASSERT_GE(c.hub_side, 0);
  ASSERT_GE(c.bus->fileno(), 0);
  EXPECT_TRUE(c.bus->reconnectable());
  std::vector<std::vector<uint8_t>> received;
  c.bus->Subscribe("DATA", [&](const std::string&, std::span<const uint8_t> d) {
    received.emplace_back(d.begin(), d.end());
    return true;
  });
  EXPECT_EQ(TestHub::ReadSubscribe(c.hub_side), "DATA");
  ASSERT_TRUE(TestHub::Publish(c.hub_side, "DATA", {1, 2, 3}));
  EXPECT_EQ(c.bus->Handle(kWaitMs / 1000.0), 1);
  ASSERT_EQ(received.size(), 1u);

  // The hub goes away: liblcm's read fails, it closes its socket and reports fileno -1.
  ::close(c.hub_side);
  EXPECT_EQ(c.bus->Handle(kWaitMs / 1000.0), -1);
  EXPECT_EQ(c.bus->fileno(), -1);
  // On main the next Handle made liblcm select() on fd -1 and abort the process.
  EXPECT_EQ(c.bus->Handle(0.0), -1);
  EXPECT_EQ(c.bus->Handle(0.5), -1);
  const std::vector<uint8_t> payload = {9};
  EXPECT_FALSE(c.bus->Publish("DATA", payload));

  // The hub is back: a new LCM instance connects and subscribes again.
  auto accepted = std::async(std::launch::async, [&hub] { return hub.Accept(); });
  std::string problem;
  ASSERT_TRUE(c.bus->Reconnect(&problem)) << problem;
  const int hub_side = accepted.get();
  ASSERT_GE(hub_side, 0);
  ASSERT_GE(c.bus->fileno(), 0);
  EXPECT_EQ(TestHub::ReadSubscribe(hub_side), "DATA");
  ASSERT_TRUE(TestHub::Publish(hub_side, "DATA", {4, 5}));
  EXPECT_EQ(c.bus->Handle(kWaitMs / 1000.0), 1);
  ASSERT_EQ(received.size(), 2u);
  EXPECT_EQ(received[1], (std::vector<uint8_t>{4, 5}));
  EXPECT_TRUE(c.bus->Publish("DATA", payload));
  ::close(hub_side);
}

TEST(LcmTcpq, NoHubAtStartIsALostConnectionNotAnAbort) {
  TestHub hub;
  hub.StopListening();  // nothing listens on the port any more: connect is refused
  LcmBus bus(hub.url());
  EXPECT_EQ(bus.fileno(), -1);
  EXPECT_EQ(bus.Handle(0.0), -1);
  EXPECT_EQ(bus.Handle(0.2), -1);
  const std::vector<uint8_t> payload = {1};
  EXPECT_FALSE(bus.Publish("X", payload));
  std::string problem;
  EXPECT_TRUE(bus.Reconnect(&problem)) << problem;  // made, but still not connected
  EXPECT_EQ(bus.fileno(), -1);
  EXPECT_EQ(bus.Handle(0.0), -1);
}

TEST(LcmTcpq, ASixteenMegabyteCommandIsRefusedAndTheNextGenuineOneAccepted) {
  TestHub hub;
  Connected c = Connect(hub);
  ASSERT_GE(c.hub_side, 0);
  const std::string channel = "SITE1.CANALID_COMMAND";
  const std::vector<uint8_t> key(32, 0x42);
  constexpr int64_t kNowUs = 1'763'700'000'000'000;
  drivers::CommandAuthenticator auth(drivers::CommandAuthOptions{.enabled = true}, key);
  int accepted = 0;
  CommandReceiver receiver(
      *c.bus, channel, auth, [] { return kNowUs; }, [&](const AcceptedCommand&) { ++accepted; });
  // The receiver subscribes to its channel as a regex, '.' escaped.
  EXPECT_EQ(TestHub::ReadSubscribe(c.hub_side), "SITE1\\.CANALID_COMMAND");
  // The hub writes 16 MB while the client reads it: on a thread, as the socket buffers are
  // smaller than the message.
  auto sent = std::async(std::launch::async, [&] {
    return TestHub::Publish(c.hub_side, channel, std::vector<uint8_t>(16u << 20, 0xab));
  });
  int handled = 0;
  for (int tries = 0; tries < 10 && handled < 1; ++tries)
    handled += std::max(0, c.bus->Handle(1.0));
  ASSERT_TRUE(sent.get());
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(receiver.count(drivers::CommandVerdict::kMalformed), 1);
  drivers::CommandFields fields;
  fields.channel = channel;
  fields.utime_us = kNowUs;
  fields.counter = 1;
  fields.sender = "ops1";
  fields.kind = 1;
  fields.reach = "pool2";
  const canalid::command_t message = BuildSignedCommand(key, fields);
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  ASSERT_TRUE(TestHub::Publish(c.hub_side, channel, bytes));
  EXPECT_EQ(c.bus->Handle(kWaitMs / 1000.0), 1);
  EXPECT_EQ(accepted, 1);
  ::close(c.hub_side);
}

}  // namespace
}  // namespace canalid::drivers
