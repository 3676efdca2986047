// CommandReceiver: every verdict through FakeBus, the same over memq:// LCM, and end to end with
// the canalid-command program writing an LCM log that the receiver reads back.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "canalid/command_t.hpp"
#include "drivers/auth/command_auth.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/command_wire.h"
#include "drivers/lcm/fake_bus.h"
#include "drivers/lcm/lcm_bus.h"
#include "tests/support/run_program.h"

namespace canalid::drivers {
namespace {

using drivers::CommandVerdict;
constexpr int64_t kNowUs = 1'763'700'000'000'000;
const std::string kChannel = "SITE1.CANALID_COMMAND";

std::vector<uint8_t> Key(const std::string& s) { return {s.begin(), s.end()}; }

drivers::CommandFields Fields(int64_t counter, int64_t utime_us = kNowUs, int8_t kind = 1) {
  drivers::CommandFields f;
  f.channel = kChannel;
  f.utime_us = utime_us;
  f.counter = counter;
  f.sender = "ops1";
  f.kind = kind;
  f.reach = "pool2";
  f.argument = "prbs";
  return f;
}

class ReceiverTest : public ::testing::Test {
 protected:
  void Send(const canalid::command_t& message, const std::string& channel = kChannel) {
    ASSERT_TRUE(PublishMessage(bus_, channel, message, buffer_));
  }
  void SendRaw(const std::vector<uint8_t>& bytes) { ASSERT_TRUE(bus_.Publish(kChannel, bytes)); }
  int HandleAll() { return bus_.Handle(0.0); }

  std::vector<uint8_t> key_ = Key("0123456789abcdef0123456789abcdef");
  FakeBus bus_;
  std::vector<uint8_t> buffer_;
  drivers::CommandAuthenticator auth_{drivers::CommandAuthOptions{.enabled = true}, key_};
  std::vector<AcceptedCommand> accepted_;
  CommandReceiver receiver_{bus_, kChannel, auth_, [] { return kNowUs; },
                            [this](const AcceptedCommand& c) { accepted_.push_back(c); }};
};

TEST_F(ReceiverTest, EveryVerdictIsCountedAndOnlyAcceptedOnesArePassedOn) {
  Send(BuildSignedCommand(key_, Fields(1)));                        // accepted
  Send(BuildSignedCommand(Key("wrong key wrong key"), Fields(2)));  // forged
  Send(BuildSignedCommand(key_, Fields(3, kNowUs - 31'000'000)));   // stale (31 s > 5 s)
  Send(BuildSignedCommand(key_, Fields(1)));                        // replayed
  auto short_mac = BuildSignedCommand(key_, Fields(4));
  short_mac.hmac.resize(16);
  short_mac.hmac_size = 16;
  Send(short_mac);                                             // malformed: bad MAC length
  SendRaw({1, 2, 3});                                          // malformed: not a command_t
  Send(BuildSignedCommand(key_, Fields(5, kNowUs, 42)));       // authentic, unknown kind
  Send(BuildSignedCommand(key_, Fields(6, kNowUs, 3)));        // accepted: reset
  Send(BuildSignedCommand(key_, Fields(7)), "OTHER_CHANNEL");  // not subscribed
  // A channel name with '.' matches only itself, not as a regex wildcard.
  Send(BuildSignedCommand(key_, Fields(8)), "SITE1xCANALID_COMMAND");
  HandleAll();

  EXPECT_EQ(receiver_.count(CommandVerdict::kAccepted), 2);
  EXPECT_EQ(receiver_.count(CommandVerdict::kBadMac), 1);
  EXPECT_EQ(receiver_.count(CommandVerdict::kStale), 1);
  EXPECT_EQ(receiver_.count(CommandVerdict::kReplayed), 1);
  EXPECT_EQ(receiver_.count(CommandVerdict::kMalformed), 2);
  EXPECT_EQ(receiver_.count(CommandVerdict::kUnknownKind), 1);
  EXPECT_EQ(receiver_.count(CommandVerdict::kDisabled), 0);
  EXPECT_EQ(receiver_.rejected(), 6);
  EXPECT_EQ(bus_.handler_failures(), 0);
  ASSERT_EQ(accepted_.size(), 2u);
  EXPECT_EQ(accepted_[0].kind, drivers::CommandKind::kStartExperiment);
  EXPECT_EQ(accepted_[0].sender, "ops1");
  EXPECT_EQ(accepted_[0].reach, "pool2");
  EXPECT_EQ(accepted_[0].argument, "prbs");
  EXPECT_EQ(accepted_[0].counter, 1);
  EXPECT_EQ(accepted_[0].utime_us, kNowUs);
  EXPECT_EQ(accepted_[1].kind, drivers::CommandKind::kResetEstimator);
  EXPECT_EQ(accepted_[1].counter, 6);
}

TEST_F(ReceiverTest, InconsistentHmacSizeIsMalformed) {
  auto message = BuildSignedCommand(key_, Fields(1));
  message.hmac_size = 32;
  message.hmac.resize(32);
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes.resize(bytes.size() - 5);  // cut inside the MAC
  SendRaw(bytes);
  HandleAll();
  EXPECT_EQ(receiver_.count(CommandVerdict::kMalformed), 1);
  EXPECT_TRUE(accepted_.empty());
}

// lcm-gen's decoder throws on a string of length 0 and on a negative array size (found by
// tests/fuzz lcm_command): such bytes are malformed, not a callback failure.
TEST_F(ReceiverTest, StringOfLengthZeroAndNegativeHmacSizeAreMalformed) {
  auto message = BuildSignedCommand(key_, Fields(1));
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  // hash (8), utime (8), counter (8), then the sender's length prefix (includes the terminator).
  std::vector<uint8_t> zero_string = bytes;
  ASSERT_EQ(zero_string[24 + 3], message.sender.size() + 1);
  zero_string[24 + 3] = 0;
  SendRaw(zero_string);
  // The hmac_size field is the 4 bytes before the 32 MAC bytes at the end.
  std::vector<uint8_t> negative_size = bytes;
  const std::size_t at = negative_size.size() - 32 - 4;
  for (std::size_t i = 0; i < 4; ++i) negative_size[at + i] = 0xFF;  // -1
  SendRaw(negative_size);
  EXPECT_EQ(HandleAll(), 2);
  EXPECT_EQ(receiver_.count(CommandVerdict::kMalformed), 2);
  EXPECT_EQ(receiver_.callback_failures(), 0);
  EXPECT_TRUE(accepted_.empty());
}

// The LCM bytes of `message` (encoded as they are, hmac_size included, whatever hmac holds).
std::vector<uint8_t> Encode(const canalid::command_t& message) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  EXPECT_EQ(message.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

void PutI32(std::vector<uint8_t>& bytes, std::size_t at, int32_t value) {
  const auto bits = static_cast<uint32_t>(value);
  for (int i = 0; i < 4; ++i)
    bytes[at + static_cast<std::size_t>(i)] = static_cast<uint8_t>(bits >> (24 - 8 * i));
}

// A 60-byte message as in the issue: a command_t with short strings, no MAC bytes and
// hmac_size = 0x7fffffff (lcm-gen's decoder resized hmac to 2 GiB before checking the length).
std::vector<uint8_t> OversizeHmacMessage() {
  canalid::command_t m;
  m.utime = kNowUs;
  m.counter = 1;
  m.sender = "operator";
  m.kind = 1;
  m.reach = "pool2";
  m.argument = "abc";
  m.hmac_size = 0;
  std::vector<uint8_t> bytes = Encode(m);
  EXPECT_EQ(bytes.size(), 60u);
  PutI32(bytes, bytes.size() - 4, 0x7fffffff);
  return bytes;
}

// Peak resident set of this process (KiB).
long PeakRssKib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

TEST(CommandWire, AcceptsGenuineMessagesAndRefusesEveryOversizeOrInconsistentLength) {
  const auto key = Key("0123456789abcdef0123456789abcdef");
  drivers::CommandFields longest = Fields(1);
  const std::string sender(drivers::kMaxCommandSenderBytes, 's');
  const std::string reach(drivers::kMaxCommandReachBytes, 'r');
  const std::string argument(drivers::kMaxCommandArgumentBytes, 'a');
  longest.sender = sender;
  longest.reach = reach;
  longest.argument = argument;
  const std::vector<uint8_t> largest = Encode(BuildSignedCommand(key, longest));
  EXPECT_EQ(largest.size(), kMaxCommandMessageBytes);
  EXPECT_TRUE(CommandWireIsBounded(largest));
  const std::vector<uint8_t> good = Encode(BuildSignedCommand(key, Fields(1)));
  ASSERT_TRUE(CommandWireIsBounded(good));

  EXPECT_FALSE(CommandWireIsBounded(OversizeHmacMessage()));
  EXPECT_FALSE(CommandWireIsBounded({}));
  // The sender's length field sits right after fingerprint, utime and counter (byte 24).
  for (int32_t length : {0, -1, INT32_MIN, 0x7fffffff, 66, 1000}) {
    std::vector<uint8_t> bad = good;
    PutI32(bad, 24, length);
    EXPECT_FALSE(CommandWireIsBounded(bad)) << "sender length " << length;
  }
  // hmac_size other than 32 (the array bytes left as they are).
  for (int32_t size : {0, -1, 16, 31, 33, 0x7fffffff}) {
    std::vector<uint8_t> bad = good;
    PutI32(bad, bad.size() - 36, size);
    EXPECT_FALSE(CommandWireIsBounded(bad)) << "hmac_size " << size;
  }
  std::vector<uint8_t> wrong_fingerprint = good;
  wrong_fingerprint[0] ^= 1;
  EXPECT_FALSE(CommandWireIsBounded(wrong_fingerprint));
  std::vector<uint8_t> trailing = good;
  trailing.push_back(0);
  EXPECT_FALSE(CommandWireIsBounded(trailing));
  std::vector<uint8_t> no_terminator = good;
  no_terminator[24 + 4 + 4] = 'x';  // "ops1" + its NUL: the NUL replaced
  EXPECT_FALSE(CommandWireIsBounded(no_terminator));
  std::vector<uint8_t> too_long(kMaxCommandMessageBytes + 1, 0);
  std::copy(good.begin(), good.begin() + 8, too_long.begin());
  EXPECT_FALSE(CommandWireIsBounded(too_long));
  for (std::size_t cut = 0; cut < good.size(); ++cut) {
    EXPECT_FALSE(CommandWireIsBounded(std::span<const uint8_t>(good.data(), cut))) << cut;
  }
}

TEST_F(ReceiverTest, OversizeArraysAreMalformedWithoutDecoding) {
  SendRaw(OversizeHmacMessage());
  std::vector<uint8_t> huge_string = Encode(BuildSignedCommand(key_, Fields(1)));
  PutI32(huge_string, 24, 0x7fffffff);
  SendRaw(huge_string);
  std::vector<uint8_t> empty_string = Encode(BuildSignedCommand(key_, Fields(1)));
  PutI32(empty_string, 24, 0);  // lcm-gen's decode threw on this (a string of length -1)
  SendRaw(empty_string);
  Send(BuildSignedCommand(key_, Fields(1)));  // then a genuine one is still accepted
  HandleAll();
  EXPECT_EQ(receiver_.count(CommandVerdict::kMalformed), 3);
  EXPECT_EQ(receiver_.count(CommandVerdict::kAccepted), 1);
  EXPECT_EQ(receiver_.callback_failures(), 0);
}

// The flood of the issue, over real LCM (memq): on main each message allocated and zeroed 2 GiB
// (about 1 s each). Now none may allocate (the process's peak RSS grows by far less than one such
// message) and the loop gets through them quickly. The bounds are generous on purpose (a loaded
// 2-core box, sanitizer builds): 64 MiB of RSS and 10 s for 2000 messages, where one message of
// main alone exceeded the first and a handful the second; the measured numbers are printed.
TEST(CommandReceiver, AFloodOfOversizeMessagesNeitherAllocatesNorStallsTheLoop) {
  LcmBus bus("memq://");
  const auto key = Key("0123456789abcdef0123456789abcdef");
  drivers::CommandAuthenticator auth(drivers::CommandAuthOptions{.enabled = true}, key);
  int accepted = 0;
  CommandReceiver receiver(
      bus, kChannel, auth, [] { return kNowUs; }, [&](const AcceptedCommand&) { ++accepted; });
  const std::vector<uint8_t> flood = OversizeHmacMessage();
  constexpr int kMessages = 2000;
  constexpr int kBatch = 50;  // below the command subscription's queue capacity
  const long rss_before = PeakRssKib();
  const auto start = std::chrono::steady_clock::now();
  double longest_handle_s = 0.0;
  int handled = 0;
  for (int sent = 0; sent < kMessages; sent += kBatch) {
    for (int i = 0; i < kBatch; ++i) ASSERT_TRUE(bus.Publish(kChannel, flood));
    const auto t0 = std::chrono::steady_clock::now();
    for (int tries = 0; tries < 10 && handled < sent + kBatch; ++tries)
      handled += std::max(0, bus.Handle(1.0));
    longest_handle_s =
        std::max(longest_handle_s,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const long rss_growth_kib = PeakRssKib() - rss_before;
  std::vector<uint8_t> buffer;
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(1)), buffer));
  for (int tries = 0; tries < 10 && accepted == 0; ++tries) bus.Handle(1.0);
  std::printf(
      "flood: %d messages in %.4f s (%.2f us each), longest Handle of %d: %.4f s, "
      "peak RSS growth %ld KiB\n",
      kMessages, elapsed_s, elapsed_s * 1e6 / kMessages, kBatch, longest_handle_s, rss_growth_kib);
  EXPECT_EQ(handled, kMessages);
  EXPECT_EQ(receiver.count(CommandVerdict::kMalformed), kMessages);
  EXPECT_EQ(accepted, 1);
  EXPECT_LT(rss_growth_kib, 64 * 1024);
  EXPECT_LT(elapsed_s, 10.0);
}

TEST(CommandReceiver, ACommandSignedForAnotherSiteIsRefused) {
  FakeBus bus;
  const auto key = Key("0123456789abcdef0123456789abcdef");
  drivers::CommandAuthenticator auth(drivers::CommandAuthOptions{.enabled = true}, key);
  CommandReceiver receiver(
      bus, kChannel, auth, [] { return kNowUs; }, [](const AcceptedCommand&) {});
  drivers::CommandFields site2 = Fields(1);
  site2.channel = "SITE2.CANALID_COMMAND";
  std::vector<uint8_t> buffer;
  // Signed for site 2 but delivered on site 1's channel (e.g. re-published by a listener).
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, site2), buffer));
  bus.Handle(0.0);
  EXPECT_EQ(receiver.count(CommandVerdict::kBadMac), 1);
  EXPECT_EQ(receiver.count(CommandVerdict::kAccepted), 0);
}

TEST(CommandReceiver, DisabledCountsEveryCommand) {
  FakeBus bus;
  const auto key = Key("0123456789abcdef");
  drivers::CommandAuthenticator off(drivers::CommandAuthOptions{}, key);
  int calls = 0;
  CommandReceiver receiver(
      bus, kChannel, off, [] { return kNowUs; }, [&](const AcceptedCommand&) { ++calls; });
  std::vector<uint8_t> buffer;
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(1)), buffer));
  bus.Handle(0.0);
  EXPECT_EQ(receiver.count(CommandVerdict::kDisabled), 1);
  EXPECT_EQ(calls, 0);
}

TEST(CommandReceiver, ThrowingCallbackOrClockIsCaughtAndCounted) {
  FakeBus bus;
  const auto key = Key("0123456789abcdef");
  drivers::CommandAuthenticator auth(drivers::CommandAuthOptions{.enabled = true}, key);
  bool clock_throws = false;
  CommandReceiver receiver(
      bus, kChannel, auth,
      [&] {
        if (clock_throws) throw std::runtime_error("clock");
        return kNowUs;
      },
      [](const AcceptedCommand&) { throw std::runtime_error("callback"); });
  std::vector<uint8_t> buffer;
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(1)), buffer));
  EXPECT_NO_THROW(bus.Handle(0.0));
  clock_throws = true;
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(2)), buffer));
  EXPECT_NO_THROW(bus.Handle(0.0));
  EXPECT_EQ(receiver.count(CommandVerdict::kAccepted), 1);
  EXPECT_EQ(receiver.callback_failures(), 2);
  EXPECT_EQ(bus.handler_failures(), 0);
}

TEST(CommandReceiver, OverMemqLcm) {
  LcmBus bus("memq://");
  const auto key = Key("0123456789abcdef0123456789abcdef");
  drivers::CommandAuthenticator auth(drivers::CommandAuthOptions{.enabled = true}, key);
  std::vector<AcceptedCommand> accepted;
  CommandReceiver receiver(
      bus, kChannel, auth, [] { return kNowUs; },
      [&](const AcceptedCommand& c) { accepted.push_back(c); });
  std::vector<uint8_t> buffer;
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(10)), buffer));
  ASSERT_TRUE(PublishMessage(bus, kChannel,
                             BuildSignedCommand(Key("forged forged forged"), Fields(11)), buffer));
  ASSERT_TRUE(PublishMessage(bus, kChannel, BuildSignedCommand(key, Fields(10)), buffer));
  // memq delivers synchronously into the queue; bounded loop, never a sleep.
  int handled = 0;
  for (int i = 0; i < 10 && handled < 3; ++i) handled += std::max(0, bus.Handle(1.0));
  EXPECT_EQ(handled, 3);
  EXPECT_EQ(receiver.count(CommandVerdict::kAccepted), 1);
  EXPECT_EQ(receiver.count(CommandVerdict::kBadMac), 1);
  EXPECT_EQ(receiver.count(CommandVerdict::kReplayed), 1);
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].counter, 10);
}

// The canalid-command program writes a log (file://...?mode=w); LcmBus reads it back losslessly.
class CommandProgram : public ::testing::Test {
 protected:
  std::filesystem::path dir_ =
      testing::TestDirectory(std::string("canalid_command.") +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::string program_ = canalid::testing::CommandProgram();

  std::filesystem::path KeyFile(const std::string& name, const std::string& text, mode_t mode) {
    auto path = dir_ / name;
    testing::WriteFile(path, text);
    ::chmod(path.c_str(), mode);
    return path;
  }
  testing::ProgramRun Send(const std::filesystem::path& key, const std::string& log,
                           const std::string& extra) {
    return testing::RunProgram(program_ + " --key " + key.string() + " --url 'file://" +
                                   (dir_ / log).string() + "?mode=w' --channel " + kChannel +
                                   " --reach pool2 --sender ops1 " + extra,
                               dir_);
  }
  // Reads one log through a receiver whose clock is the real one (the program signs with it; the
  // window is wide so a slow machine cannot make the genuine command stale).
  void Receive(const std::string& log, drivers::CommandAuthenticator& auth,
               std::vector<AcceptedCommand>& accepted) {
    LcmBus bus("file://" + (dir_ / log).string() + "?speed=0");
    CommandReceiver receiver(
        bus, kChannel, auth,
        [] {
          return std::chrono::duration_cast<std::chrono::microseconds>(
                     std::chrono::system_clock::now().time_since_epoch())
              .count();
        },
        [&](const AcceptedCommand& c) { accepted.push_back(c); });
    for (int i = 0; i < 10; ++i) {
      if (bus.Handle(2.0) <= 0) break;
    }
    counts_.clear();
    for (int v = 0; v < drivers::kNumCommandVerdicts; ++v) {
      counts_.push_back(receiver.count(static_cast<CommandVerdict>(v)));
    }
  }
  int64_t Count(CommandVerdict v) const { return counts_.at(static_cast<std::size_t>(v)); }
  std::vector<int64_t> counts_;
};

TEST_F(CommandProgram, SignedCommandsEndToEnd) {
  const std::string hex_key = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff\n";
  const auto key = KeyFile("key", hex_key, 0600);
  const auto wrong =
      KeyFile("wrong", "ffeeddccbbaa99887766554433221100ffeeddccbbaa99887766554433221100\n", 0600);
  auto run = Send(key, "genuine.lcmlog", "start --counter 5 --argument prbs");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("sent start"), std::string::npos) << run.out;
  ASSERT_EQ(Send(key, "replay.lcmlog", "start --counter 5").exit_code, 0);
  ASSERT_EQ(Send(wrong, "forged.lcmlog", "stop --counter 6").exit_code, 0);
  ASSERT_EQ(Send(key, "stale.lcmlog", "reset --counter 7 --utime-us 1000000").exit_code, 0);

  // The daemon decodes the same hex key.
  std::vector<uint8_t> daemon_key;
  for (std::size_t i = 0; i + 1 < hex_key.size(); i += 2) {
    daemon_key.push_back(static_cast<uint8_t>(std::stoi(hex_key.substr(i, 2), nullptr, 16)));
  }
  drivers::CommandAuthenticator auth(
      drivers::CommandAuthOptions{.enabled = true, .max_clock_skew_s = 600.0}, daemon_key);
  std::vector<AcceptedCommand> accepted;
  Receive("genuine.lcmlog", auth, accepted);
  EXPECT_EQ(Count(CommandVerdict::kAccepted), 1);
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].kind, drivers::CommandKind::kStartExperiment);
  EXPECT_EQ(accepted[0].argument, "prbs");
  EXPECT_EQ(accepted[0].counter, 5);
  Receive("replay.lcmlog", auth, accepted);
  EXPECT_EQ(Count(CommandVerdict::kReplayed), 1);
  Receive("forged.lcmlog", auth, accepted);
  EXPECT_EQ(Count(CommandVerdict::kBadMac), 1);
  Receive("stale.lcmlog", auth, accepted);
  EXPECT_EQ(Count(CommandVerdict::kStale), 1);
  EXPECT_EQ(accepted.size(), 1u);
}

TEST_F(CommandProgram, RefusesAGroupReadableKey) {
  const auto key = KeyFile("open-key", "00112233445566778899aabbccddeeff\n", 0640);
  const auto run = Send(key, "none.lcmlog", "start");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("chmod 600"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "none.lcmlog"));
}

}  // namespace
}  // namespace canalid::drivers
