// CommandReceiver: every verdict through FakeBus, the same over memq:// LCM, and end to end with
// the canalid-command program writing an LCM log that the receiver reads back.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "canalid/command_t.hpp"
#include "core/command_auth.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/fake_bus.h"
#include "drivers/lcm/lcm_bus.h"
#include "support/run_program.h"

namespace canalid::drivers {
namespace {

using core::CommandVerdict;
constexpr int64_t kNowUs = 1'763'700'000'000'000;
const std::string kChannel = "SITE1.CANALID_COMMAND";

std::vector<uint8_t> Key(const std::string& s) { return {s.begin(), s.end()}; }

core::CommandFields Fields(int64_t counter, int64_t utime_us = kNowUs, int8_t kind = 1) {
  core::CommandFields f;
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
  core::CommandAuthenticator auth_{core::CommandAuthOptions{.enabled = true}, key_};
  std::vector<AcceptedCommand> accepted_;
  CommandReceiver receiver_{bus_, kChannel, auth_, [] { return kNowUs; },
                            [this](const AcceptedCommand& c) { accepted_.push_back(c); }};
};

TEST_F(ReceiverTest, EveryVerdictIsCountedAndOnlyAcceptedOnesArePassedOn) {
  Send(BuildSignedCommand(key_, Fields(1)));                        // accepted
  Send(BuildSignedCommand(Key("wrong key wrong key"), Fields(2)));  // forged
  Send(BuildSignedCommand(key_, Fields(3, kNowUs - 31'000'000)));   // stale (31 s > 30 s)
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
  EXPECT_EQ(accepted_[0].kind, core::CommandKind::kStartExperiment);
  EXPECT_EQ(accepted_[0].sender, "ops1");
  EXPECT_EQ(accepted_[0].reach, "pool2");
  EXPECT_EQ(accepted_[0].argument, "prbs");
  EXPECT_EQ(accepted_[0].counter, 1);
  EXPECT_EQ(accepted_[0].utime_us, kNowUs);
  EXPECT_EQ(accepted_[1].kind, core::CommandKind::kResetEstimator);
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

TEST(CommandReceiver, DisabledCountsEveryCommand) {
  FakeBus bus;
  const auto key = Key("0123456789abcdef");
  core::CommandAuthenticator off(core::CommandAuthOptions{}, key);
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
  core::CommandAuthenticator auth(core::CommandAuthOptions{.enabled = true}, key);
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
  core::CommandAuthenticator auth(core::CommandAuthOptions{.enabled = true}, key);
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
  std::string program_ = std::string(CANALID_BINARY_DIR) + "/daemon/command/canalid-command";

  std::filesystem::path KeyFile(const std::string& name, const std::string& text, mode_t mode) {
    const auto path = dir_ / name;
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
  void Receive(const std::string& log, core::CommandAuthenticator& auth,
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
    for (int v = 0; v < core::kNumCommandVerdicts; ++v) {
      counts_.push_back(receiver.count(static_cast<CommandVerdict>(v)));
    }
  }
  int64_t Count(CommandVerdict v) const { return counts_.at(static_cast<std::size_t>(v)); }
  std::vector<int64_t> counts_;
};

TEST_F(CommandProgram, SignedCommandsEndToEnd) {
  const std::string hex_key = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff\n";
  const auto key = KeyFile("key", hex_key, 0600);
  const auto wrong = KeyFile("wrong", "ffeeddccbbaa99887766554433221100\n", 0600);
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
  core::CommandAuthenticator auth(
      core::CommandAuthOptions{.enabled = true, .max_clock_skew_s = 600.0}, daemon_key);
  std::vector<AcceptedCommand> accepted;
  Receive("genuine.lcmlog", auth, accepted);
  EXPECT_EQ(Count(CommandVerdict::kAccepted), 1);
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].kind, core::CommandKind::kStartExperiment);
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
