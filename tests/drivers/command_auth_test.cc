// Command authentication: the signed byte layout against bytes written out by hand from the
// documented layout, and every verdict of the verifier on commands built to provoke it.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/auth/command_auth.h"
#include "drivers/auth/hmac.h"

namespace canalid::drivers {
namespace {

constexpr int64_t kNowUs = 1'763'700'000'000'000;  // 2025-11-21, an arbitrary daemon clock

std::vector<uint8_t> Key(const std::string& s) { return {s.begin(), s.end()}; }

struct SignedCommand {
  CommandFields fields;
  Sha256Digest mac;
  // Rebinds fields.mac to this object's mac (after copies).
  CommandFields Get() {
    CommandFields f = fields;
    f.mac = mac;
    return f;
  }
};

SignedCommand Make(const std::vector<uint8_t>& key, int64_t counter, int64_t utime_us = kNowUs,
                   int8_t kind = 1, std::string_view sender = "ops1",
                   std::string_view reach = "pool2", std::string_view channel = "SITE1.COMMAND") {
  SignedCommand c;
  c.fields.channel = channel;
  c.fields.utime_us = utime_us;
  c.fields.counter = counter;
  c.fields.sender = sender;
  c.fields.kind = kind;
  c.fields.reach = reach;
  c.fields.argument = "prbs";
  c.mac = SignCommand(key, c.fields);
  return c;
}

TEST(CanonicalCommandBytes, MatchesTheDocumentedLayout) {
  CommandFields f;
  f.channel = "S1.C";
  f.kind = 3;
  f.reach = "p2";
  f.sender = "op";
  f.counter = 0x0102030405060708;
  f.utime_us = -2;  // two's complement, big-endian
  f.argument = "";
  std::vector<uint8_t> expected = {'c', 'a', 'n', 'a', 'l', 'i', 'd', '-', 'c',
                                   'o', 'm', 'm', 'a', 'n', 'd', '-', 'v', '2'};
  const std::vector<uint8_t> rest = {0,    0,    0,    4,    'S',  '1',  '.',  'C',   // channel
                                     3,                                               // kind
                                     0,    0,    0,    2,    'p',  '2',               // reach
                                     0,    0,    0,    2,    'o',  'p',               // sender
                                     1,    2,    3,    4,    5,    6,    7,    8,     // counter
                                     0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xfe,  // utime_us
                                     0,    0,    0,    0};                            // argument
  expected.insert(expected.end(), rest.begin(), rest.end());
  std::vector<uint8_t> out = {9, 9};  // cleared first
  CanonicalCommandBytes(f, out);
  EXPECT_EQ(out, expected);
  EXPECT_EQ(SignCommand(Key("k"), f), HmacSha256::Mac(Key("k"), expected));
  // The tag itself, computed independently of this code with Python's hmac module:
  //   m = b"canalid-command-v2" + struct.pack(">I", 4) + b"S1.C" + bytes([3]) +
  //       struct.pack(">I", 2) + b"p2" + struct.pack(">I", 2) + b"op" +
  //       struct.pack(">q", 0x0102030405060708) + struct.pack(">q", -2) + struct.pack(">I", 0)
  //   hmac.new(b"k", m, hashlib.sha256).digest()
  // so the wire format does not depend on the library that computes the MAC.
  const Sha256Digest tag = SignCommand(Key("k"), f);
  const Sha256Digest known = {0xf4, 0xd3, 0xf7, 0x01, 0x33, 0x15, 0x2e, 0xfd, 0x08, 0xfa, 0xef,
                              0x11, 0x3f, 0x95, 0x58, 0x3c, 0xec, 0x5a, 0x43, 0x53, 0x23, 0x6a,
                              0x90, 0x86, 0x9d, 0xb6, 0x4a, 0x79, 0x7b, 0x4a, 0x9e, 0xb2};
  EXPECT_EQ(tag, known);
}

TEST(CanonicalCommandBytes, LengthPrefixesSeparateFields) {
  // reach "ab" + sender "c" must not sign like reach "a" + sender "bc".
  CommandFields a, b;
  a.reach = "ab";
  a.sender = "c";
  b.reach = "a";
  b.sender = "bc";
  EXPECT_NE(SignCommand(Key("k"), a), SignCommand(Key("k"), b));
}

class CommandAuthenticatorTest : public ::testing::Test {
 protected:
  std::vector<uint8_t> key_ = Key("0123456789abcdef0123456789abcdef");
  CommandAuthenticator auth_{CommandAuthOptions{.enabled = true, .max_clock_skew_s = 30.0}, key_};
};

TEST_F(CommandAuthenticatorTest, AcceptsAGenuineCommand) {
  auto c = Make(key_, 1);
  EXPECT_EQ(auth_.Verify(c.Get(), kNowUs), CommandVerdict::kAccepted);
  EXPECT_EQ(auth_.last_counters().at("ops1"), 1);
}

TEST_F(CommandAuthenticatorTest, RejectsForgedAndAlteredCommands) {
  auto forged = Make(Key("not the key"), 1);
  EXPECT_EQ(auth_.Verify(forged.Get(), kNowUs), CommandVerdict::kBadMac);
  auto altered = Make(key_, 2);
  CommandFields f = altered.Get();
  f.reach = "pool3";  // signed for pool2
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kBadMac);
  f = altered.Get();
  f.kind = 2;
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kBadMac);
  // Flip one bit of the MAC itself.
  Sha256Digest flipped = altered.mac;
  flipped[31] ^= 1;
  f = altered.Get();
  f.mac = flipped;
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kBadMac);
  // Nothing above was accepted, so no counter was recorded.
  EXPECT_TRUE(auth_.last_counters().empty());
}

TEST_F(CommandAuthenticatorTest, RefusesATagDifferingInOneByte) {
  auto c = Make(key_, 1);
  for (std::size_t i : {std::size_t{0}, c.mac.size() - 1}) {
    SignedCommand altered = c;
    altered.mac[i] ^= 0x01;
    EXPECT_EQ(auth_.Verify(altered.Get(), kNowUs), CommandVerdict::kBadMac) << "byte " << i;
  }
  // The untouched command is still accepted: the refusals were the altered bytes.
  EXPECT_EQ(auth_.Verify(c.Get(), kNowUs), CommandVerdict::kAccepted);
}

TEST_F(CommandAuthenticatorTest, RefusesATagOfTheWrongLength) {
  auto c = Make(key_, 1);
  // One byte short (a right prefix) and one byte more (the right tag, then a byte).
  CommandFields f = c.Get();
  f.mac = std::span<const uint8_t>(c.mac.data(), c.mac.size() - 1);
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kMalformed);
  std::vector<uint8_t> longer(c.mac.begin(), c.mac.end());
  longer.push_back(0);
  f.mac = longer;
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kMalformed);
  EXPECT_TRUE(auth_.last_counters().empty());
}

TEST_F(CommandAuthenticatorTest, ForgeriesDoNotBurnCounters) {
  auto forged = Make(Key("attacker"), 1'000'000);
  EXPECT_EQ(auth_.Verify(forged.Get(), kNowUs), CommandVerdict::kBadMac);
  auto genuine = Make(key_, 5);
  EXPECT_EQ(auth_.Verify(genuine.Get(), kNowUs), CommandVerdict::kAccepted);
}

TEST_F(CommandAuthenticatorTest, StaleAtTheEdgeOfTheWindow) {
  // 30 s exactly is inside the window, 1 us more is not, in both directions.
  auto edge_old = Make(key_, 1, kNowUs - 30'000'000);
  auto edge_new = Make(key_, 2, kNowUs + 30'000'000);
  auto too_old = Make(key_, 3, kNowUs - 30'000'001);
  auto too_new = Make(key_, 4, kNowUs + 30'000'001);
  EXPECT_EQ(auth_.Verify(too_old.Get(), kNowUs), CommandVerdict::kStale);
  EXPECT_EQ(auth_.Verify(too_new.Get(), kNowUs), CommandVerdict::kStale);
  EXPECT_EQ(auth_.Verify(edge_old.Get(), kNowUs), CommandVerdict::kAccepted);
  EXPECT_EQ(auth_.Verify(edge_new.Get(), kNowUs), CommandVerdict::kAccepted);
  // Extreme timestamps do not overflow the comparison.
  auto ancient = Make(key_, 9, INT64_MIN);
  EXPECT_EQ(auth_.Verify(ancient.Get(), INT64_MAX), CommandVerdict::kStale);
}

TEST_F(CommandAuthenticatorTest, ReplaysAreRejectedPerSender) {
  auto first = Make(key_, 7);
  EXPECT_EQ(auth_.Verify(first.Get(), kNowUs), CommandVerdict::kAccepted);
  EXPECT_EQ(auth_.Verify(first.Get(), kNowUs), CommandVerdict::kReplayed);
  auto lower = Make(key_, 6);
  EXPECT_EQ(auth_.Verify(lower.Get(), kNowUs), CommandVerdict::kReplayed);
  // Another sender has its own counter.
  auto other = Make(key_, 1, kNowUs, 1, "ops2");
  EXPECT_EQ(auth_.Verify(other.Get(), kNowUs), CommandVerdict::kAccepted);
  auto next = Make(key_, 8);
  EXPECT_EQ(auth_.Verify(next.Get(), kNowUs), CommandVerdict::kAccepted);
}

TEST_F(CommandAuthenticatorTest, RestoredCountersRejectReplaysAfterARestart) {
  auto c = Make(key_, 41);
  EXPECT_TRUE(auth_.RestoreCounter("ops1", 41, kNowUs));
  EXPECT_TRUE(auth_.RestoreCounter("ops1", 3, kNowUs));  // lower: ignored
  EXPECT_EQ(auth_.Verify(c.Get(), kNowUs), CommandVerdict::kReplayed);
}

TEST_F(CommandAuthenticatorTest, ASignatureForAnotherChannelIsRefused) {
  // Same key, same fields, signed for site 2's channel: site 1's daemon refuses it.
  auto site2 = Make(key_, 1, kNowUs, 1, "ops1", "pool2", "SITE2.COMMAND");
  CommandFields f = site2.Get();
  f.channel = "SITE1.COMMAND";  // the receiver fills in its own channel
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kBadMac);
  f.channel = "SITE2.COMMAND";
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kAccepted);
}

// A key holder signs a command as another operator's `sender` with counter INT64_MAX; on main it
// was accepted and that sender could never send again (the counter was persisted too).
TEST_F(CommandAuthenticatorTest, ALockoutAttemptIsRefusedAndTheGenuineSenderCarriesOn) {
  auto genuine1 = Make(key_, kNowUs - 1'000'000);  // canalid-command's default: its clock in us
  EXPECT_EQ(auth_.Verify(genuine1.Get(), kNowUs), CommandVerdict::kAccepted);
  for (int64_t counter : {INT64_MAX, INT64_MAX / 2, kNowUs + 30'000'001}) {
    auto lockout = Make(key_, counter);
    EXPECT_EQ(auth_.Verify(lockout.Get(), kNowUs), CommandVerdict::kCounterAhead) << counter;
  }
  EXPECT_EQ(auth_.last_counters().at("ops1"), kNowUs - 1'000'000);
  auto genuine2 = Make(key_, kNowUs);
  EXPECT_EQ(auth_.Verify(genuine2.Get(), kNowUs), CommandVerdict::kAccepted);
  // The most a key holder can do: push the counter to the edge of the window, which the
  // genuine sender's clock-based counter passes once the window has gone by.
  auto edge = Make(key_, kNowUs + 30'000'000);
  EXPECT_EQ(auth_.Verify(edge.Get(), kNowUs), CommandVerdict::kAccepted);
  auto later = Make(key_, kNowUs + 30'000'001, kNowUs + 30'000'001);
  EXPECT_EQ(auth_.Verify(later.Get(), kNowUs + 30'000'001), CommandVerdict::kAccepted);
  // Explicit small counters stay usable.
  auto other = Make(key_, 1, kNowUs, 1, "ops2");
  EXPECT_EQ(auth_.Verify(other.Get(), kNowUs), CommandVerdict::kAccepted);
}

TEST_F(CommandAuthenticatorTest, RestoredCountersOutOfReachAreRefused) {
  EXPECT_FALSE(auth_.RestoreCounter("ops1", INT64_MAX, kNowUs));
  EXPECT_FALSE(auth_.RestoreCounter("ops1", kNowUs + 30'000'001, kNowUs));
  EXPECT_FALSE(auth_.RestoreCounter("ops1", 0, kNowUs));
  EXPECT_FALSE(auth_.RestoreCounter("", 5, kNowUs));
  EXPECT_FALSE(auth_.RestoreCounter(std::string(kMaxCommandSenderBytes + 1, 's'), 5, kNowUs));
  EXPECT_TRUE(auth_.last_counters().empty());
  EXPECT_TRUE(auth_.RestoreCounter("ops1", kNowUs + 30'000'000, kNowUs));
}

TEST_F(CommandAuthenticatorTest, MalformedCommands) {
  auto c = Make(key_, 1);
  CommandFields f = c.Get();
  f.mac = std::span<const uint8_t>(c.mac.data(), 16);  // truncated MAC
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kMalformed);
  f.mac = {};
  EXPECT_EQ(auth_.Verify(f, kNowUs), CommandVerdict::kMalformed);
  auto no_sender = Make(key_, 1, kNowUs, 1, "");
  EXPECT_EQ(auth_.Verify(no_sender.Get(), kNowUs), CommandVerdict::kMalformed);
  auto zero_counter = Make(key_, 0);
  EXPECT_EQ(auth_.Verify(zero_counter.Get(), kNowUs), CommandVerdict::kMalformed);
  const std::string long_reach(kMaxCommandReachBytes + 1, 'r');
  auto too_long = Make(key_, 1, kNowUs, 1, "ops1", long_reach);
  EXPECT_EQ(auth_.Verify(too_long.Get(), kNowUs), CommandVerdict::kMalformed);
}

TEST_F(CommandAuthenticatorTest, AuthenticUnknownKind) {
  auto c = Make(key_, 1, kNowUs, 9);
  EXPECT_EQ(auth_.Verify(c.Get(), kNowUs), CommandVerdict::kUnknownKind);
  auto zero = Make(key_, 2, kNowUs, 0);
  EXPECT_EQ(auth_.Verify(zero.Get(), kNowUs), CommandVerdict::kUnknownKind);
}

TEST(CommandAuthenticator, DisabledRejectsEvenGenuineCommands) {
  const auto key = Key("0123456789abcdef");
  CommandAuthenticator off(CommandAuthOptions{}, key);  // enabled = false by default
  auto c = Make(key, 1);
  EXPECT_EQ(off.Verify(c.Get(), kNowUs), CommandVerdict::kDisabled);
}

TEST(CommandAuthenticator, RejectsBadOptions) {
  EXPECT_THROW(CommandAuthenticator(CommandAuthOptions{.enabled = true}, {}),
               std::invalid_argument);
  EXPECT_THROW(
      CommandAuthenticator(CommandAuthOptions{.enabled = true, .max_clock_skew_s = 0.0}, Key("k")),
      std::invalid_argument);
  EXPECT_STREQ(CommandVerdictName(CommandVerdict::kUnknownKind), "unknown_kind");
  EXPECT_STREQ(CommandVerdictName(CommandVerdict::kCounterAhead), "counter_ahead");
}

}  // namespace
}  // namespace canalid::drivers
