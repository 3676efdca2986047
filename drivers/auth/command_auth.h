#pragma once
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/auth/hmac.h"
#include "drivers/auth/secret_bytes.h"

namespace canalid::drivers {

/// Operator command kinds (the KIND_* constants of canalid.command_t).
enum class CommandKind : int8_t {
  kStartExperiment = 1,
  kAbortExperiment = 2,
  kResetEstimator = 3,
  kPublishConfig = 4,
};

/// The fields of a command that the MAC covers, plus the MAC itself. Views: valid during the call.
struct CommandFields {
  /// The LCM channel the command is published on (the daemon's prefix + "COMMAND", e.g.
  /// "SITE1.CANALID_COMMAND"): signed, so a command for one site or daemon is refused by another
  /// that shares the key. Not a field of command_t: the receiver fills in its own channel.
  std::string_view channel;
  int64_t utime_us = 0;  ///< sender's clock, us since the Unix epoch
  int64_t counter = 0;   ///< > 0, strictly increasing per sender
  std::string_view sender;
  int8_t kind = 0;  ///< a CommandKind value
  std::string_view reach;
  std::string_view argument;
  std::span<const uint8_t> mac;  ///< HMAC-SHA256, 32 bytes
};

/// Limits on the variable-length fields; longer ones are malformed.
inline constexpr std::size_t kMaxCommandSenderBytes = 64;
inline constexpr std::size_t kMaxCommandReachBytes = 64;
inline constexpr std::size_t kMaxCommandArgumentBytes = 1024;

/// The signed bytes of a command (docs/lcm-channels.md, "Command signature"), all integers
/// big-endian:
///   "canalid-command-v2" (18 ASCII bytes, no terminator) | u32 length + channel bytes |
///   kind (1 byte, two's complement) | u32 length + reach bytes | u32 length + sender bytes |
///   counter (i64) | utime_us (i64) | u32 length + argument bytes.
/// Length prefixes make the layout unambiguous (no two field tuples give the same bytes).
/// Appends to `out` (cleared first); fields.mac is not used.
void CanonicalCommandBytes(const CommandFields& fields, std::vector<uint8_t>& out);

/// HMAC-SHA256 of CanonicalCommandBytes(fields) under `key`.
/// @throws std::runtime_error when OpenSSL fails (HmacSha256::Mac).
Sha256Digest SignCommand(std::span<const uint8_t> key, const CommandFields& fields);

/// Outcome of verifying one command; every one is counted by the receiver.
enum class CommandVerdict {
  kAccepted = 0,
  kBadMac,       ///< the MAC does not match (wrong key, altered field)
  kStale,        ///< |utime - now| > max_clock_skew_s
  kReplayed,     ///< counter <= the last accepted counter of this sender
  kMalformed,    ///< undecodable, MAC not 32 bytes, empty sender, counter <= 0, field too long
  kUnknownKind,  ///< authentic, but kind is not a CommandKind
  kDisabled,     ///< commands are off in the config
  /// authentic, but the counter is ahead of the daemon clock (in us) by more than
  /// max_clock_skew_s: it would push the sender's counter out of reach of its next command
  kCounterAhead,
};
inline constexpr int kNumCommandVerdicts = 8;
/// "accepted", "bad_mac", "stale", "replayed", "malformed", "unknown_kind", "disabled",
/// "counter_ahead".
const char* CommandVerdictName(CommandVerdict verdict);

struct CommandAuthOptions {
  bool enabled = false;           ///< commands are off by default
  double max_clock_skew_s = 5.0;  ///< > 0: accepted |sender clock - daemon clock| (config default)

  /// @throws std::invalid_argument when max_clock_skew_s is not finite and > 0.
  void Validate() const;
};

/// Verifies operator commands: checks in the order disabled, malformed, MAC (constant-time
/// compare), kind, timestamp window, counter bound, replay. Only an accepted command advances its
/// sender's counter, so a forged or stale message cannot burn counters of a real sender.
///
/// Counter bound: with one shared key any key holder can sign for any `sender`, so a counter is
/// accepted only if it is at most now_us + max_clock_skew_s (in us), the daemon clock read as a
/// microsecond count. canalid-command's default counter is the sender's clock in us, which
/// passes; small explicit counters (1, 2, ...) pass too. A key holder can therefore push another
/// sender's counter at most max_clock_skew_s ahead of the clock (that sender's next time-based
/// counter is accepted at most that long later), never to INT64_MAX.
///
/// A restart forgets the counters unless they are restored (RestoreCounter, which applies the
/// same bound); the timestamp window still bounds replays across a restart to max_clock_skew_s.
/// The key is copied into SecretBytes and wiped when the authenticator is destroyed. Pure (time
/// is passed in), not thread-safe; allocates only for a new sender and in CanonicalCommandBytes's
/// buffer.
class CommandAuthenticator final {
 public:
  /// @param key the shared secret (at least 1 byte), copied (the caller wipes its own copy).
  /// @throws std::invalid_argument on a bad option or an empty key while enabled.
  CommandAuthenticator(const CommandAuthOptions& options, std::span<const uint8_t> key);

  /// @throws std::runtime_error when OpenSSL fails to compute the MAC (HmacSha256::Mac).
  CommandVerdict Verify(const CommandFields& fields, int64_t now_us);

  /// Last accepted counter of each sender (to persist across restarts).
  const std::map<std::string, int64_t, std::less<>>& last_counters() const { return counters_; }
  /// Sets a sender's last accepted counter (from the state directory) if it is higher than the one
  /// known. Refused (false, nothing changed) when the sender is empty or longer than
  /// kMaxCommandSenderBytes, or the counter is <= 0 or above now_us + max_clock_skew_s: a
  /// persisted counter pushed out of reach does not survive a restart.
  bool RestoreCounter(const std::string& sender, int64_t counter, int64_t now_us);
  const CommandAuthOptions& options() const { return options_; }

 private:
  bool CounterAhead(int64_t counter, int64_t now_us) const;

  CommandAuthOptions options_;
  SecretBytes key_;
  std::vector<uint8_t> scratch_;
  std::map<std::string, int64_t, std::less<>> counters_;
};

}  // namespace canalid::drivers
