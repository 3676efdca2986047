// Operator commands as the daemon receives them (drivers/lcm/command_receiver.h): the bytes are
// published on a FakeBus to a CommandReceiver, which decodes them as canalid.command_t and
// verifies them with a drivers::CommandAuthenticator under the fuzz key (lcm_seeds.cc signs the
// seeds with it).  Properties: every message is counted exactly once; an accepted command is the
// one decoded.  Then, when the bytes decode, the same fields signed with the key and stamped with
// the daemon's clock are sent again: the MAC of a well-formed command must verify (no bad_mac,
// no stale), so mutated fields also reach the verifier's checks after the MAC.
#include <canalid/command_t.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivers/auth/command_auth.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/fake_bus.h"
#include "tests/fuzz/fuzz_check.h"
#include "tests/fuzz/lcm_fuzz_key.h"

namespace {

using canalid::drivers::CommandVerdict;
using canalid::fuzz::Check;

struct Outcome {
  std::array<int64_t, canalid::drivers::kNumCommandVerdicts> counts{};
  int64_t callback_failures = 0;
  std::optional<canalid::drivers::AcceptedCommand> accepted;
  int64_t Total() const {
    int64_t total = callback_failures;
    for (int64_t c : counts) total += c;
    return total;
  }
};

Outcome Deliver(const uint8_t* data, std::size_t size) {
  canalid::drivers::FakeBus bus;
  canalid::drivers::CommandAuthenticator authenticator({true, 30.0}, canalid::fuzz::kCommandKey);
  Outcome outcome;
  canalid::drivers::CommandReceiver receiver(
      bus, canalid::fuzz::kCommandChannel, authenticator, [] { return canalid::fuzz::kNowUs; },
      [&](const canalid::drivers::AcceptedCommand& c) { outcome.accepted = c; });
  Check(bus.Publish(canalid::fuzz::kCommandChannel, std::span<const uint8_t>(data, size)),
        "the fake bus takes the message");
  Check(bus.Handle(0.0) == 1, "the message is delivered once");
  for (int v = 0; v < canalid::drivers::kNumCommandVerdicts; ++v)
    outcome.counts[static_cast<std::size_t>(v)] = receiver.count(static_cast<CommandVerdict>(v));
  outcome.callback_failures = receiver.callback_failures();
  Check(outcome.Total() == 1, "every message is counted exactly once");
  Check(outcome.accepted.has_value() == (outcome.counts[0] == 1),
        "the callback runs for accepted commands only");
  return outcome;
}

int64_t Count(const Outcome& outcome, CommandVerdict verdict) {
  return outcome.counts[static_cast<std::size_t>(verdict)];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Outcome first = Deliver(data, size);
  canalid::command_t message;
  if (!canalid::drivers::DecodeMessage(std::span<const uint8_t>(data, size), message)) return 0;
  if (first.accepted) {
    Check(first.accepted->utime_us == message.utime && first.accepted->counter == message.counter &&
              first.accepted->sender == message.sender && first.accepted->reach == message.reach &&
              first.accepted->argument == message.argument &&
              static_cast<int>(first.accepted->kind) == message.kind,
          "the accepted command is the one decoded");
  }
  // The same fields, signed with the key at the daemon's time.  LCM encodes strings as C strings
  // (up to the first NUL), so fields holding a NUL cannot be sent again as they were decoded.
  for (const std::string* s : {&message.sender, &message.reach, &message.argument})
    if (s->find('\0') != std::string::npos) return 0;
  message.utime = canalid::fuzz::kNowUs;
  message = canalid::drivers::BuildSignedCommand(
      canalid::fuzz::kCommandKey,
      canalid::drivers::CommandFieldsOf(message, canalid::fuzz::kCommandChannel));
  std::vector<uint8_t> signed_bytes(static_cast<std::size_t>(message.getEncodedSize()));
  Check(message.encode(signed_bytes.data(), 0, static_cast<int>(signed_bytes.size())) ==
            static_cast<int>(signed_bytes.size()),
        "a decoded command encodes again");
  const Outcome second = Deliver(signed_bytes.data(), signed_bytes.size());
  Check(Count(second, CommandVerdict::kBadMac) == 0, "a command signed with the key verifies");
  Check(Count(second, CommandVerdict::kStale) == 0, "a command at the daemon's time is fresh");
  return 0;
}
