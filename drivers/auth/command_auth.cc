#include "drivers/auth/command_auth.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers/auth/hmac.h"

namespace canalid::drivers {
namespace {

constexpr std::string_view kDomain = "canalid-command-v2";

// Writes into a buffer sized up front: GCC 12 reports a false stringop-overflow for
// vector::insert after clear() at -O2.
class ByteWriter {
 public:
  explicit ByteWriter(uint8_t* out) : out_(out) {}
  void U32(uint32_t value) {
    for (int shift = 24; shift >= 0; shift -= 8) *out_++ = static_cast<uint8_t>(value >> shift);
  }
  void I64(int64_t value) {
    const auto bits = static_cast<uint64_t>(value);
    for (int shift = 56; shift >= 0; shift -= 8) *out_++ = static_cast<uint8_t>(bits >> shift);
  }
  void Raw(std::string_view s) {
    for (char ch : s) *out_++ = static_cast<uint8_t>(ch);
  }
  void String(std::string_view s) {
    U32(static_cast<uint32_t>(s.size()));
    Raw(s);
  }
  void Byte(uint8_t b) { *out_++ = b; }

 private:
  uint8_t* out_;
};

bool IsKnownKind(int8_t kind) {
  return kind >= static_cast<int8_t>(CommandKind::kStartExperiment) &&
         kind <= static_cast<int8_t>(CommandKind::kPublishConfig);
}

}  // namespace

void CanonicalCommandBytes(const CommandFields& fields, std::vector<uint8_t>& out) {
  // The kind byte, four string lengths (u32) and two i64, then the strings.
  constexpr std::size_t kFixedBytes = 1 + 4 * sizeof(uint32_t) + 2 * sizeof(int64_t);
  const std::size_t size = kDomain.size() + kFixedBytes + fields.channel.size() +
                           fields.reach.size() + fields.sender.size() + fields.argument.size();
  out.resize(size);
  ByteWriter w(out.data());
  w.Raw(kDomain);
  w.String(fields.channel);
  w.Byte(static_cast<uint8_t>(fields.kind));
  w.String(fields.reach);
  w.String(fields.sender);
  w.I64(fields.counter);
  w.I64(fields.utime_us);
  w.String(fields.argument);
}

Sha256Digest SignCommand(std::span<const uint8_t> key, const CommandFields& fields) {
  std::vector<uint8_t> bytes;
  CanonicalCommandBytes(fields, bytes);
  return HmacSha256::Mac(key, bytes);
}

const char* CommandVerdictName(CommandVerdict verdict) {
  switch (verdict) {
    case CommandVerdict::kAccepted:
      return "accepted";
    case CommandVerdict::kBadMac:
      return "bad_mac";
    case CommandVerdict::kStale:
      return "stale";
    case CommandVerdict::kReplayed:
      return "replayed";
    case CommandVerdict::kMalformed:
      return "malformed";
    case CommandVerdict::kUnknownKind:
      return "unknown_kind";
    case CommandVerdict::kDisabled:
      return "disabled";
    case CommandVerdict::kCounterAhead:
      return "counter_ahead";
  }
  return "unknown";
}

void CommandAuthOptions::Validate() const {
  if (!std::isfinite(max_clock_skew_s) || max_clock_skew_s <= 0.0) {
    throw std::invalid_argument("commands.max_clock_skew_s = " + std::to_string(max_clock_skew_s) +
                                " is out of range: must be finite and > 0 s");
  }
}

CommandAuthenticator::CommandAuthenticator(const CommandAuthOptions& options,
                                           std::span<const uint8_t> key)
    : options_(options), key_(key) {
  options_.Validate();
  if (options_.enabled && key_.empty()) {
    throw std::invalid_argument("command key is empty: commands need a key of at least 1 byte");
  }
  scratch_.reserve(256);
}

CommandVerdict CommandAuthenticator::Verify(const CommandFields& fields, int64_t now_us) {
  if (!options_.enabled) return CommandVerdict::kDisabled;
  if (fields.mac.size() != sizeof(Sha256Digest) || fields.sender.empty() ||
      fields.sender.size() > kMaxCommandSenderBytes ||
      fields.reach.size() > kMaxCommandReachBytes ||
      fields.argument.size() > kMaxCommandArgumentBytes || fields.counter <= 0) {
    return CommandVerdict::kMalformed;
  }
  CanonicalCommandBytes(fields, scratch_);
  const Sha256Digest expected = HmacSha256::Mac(key_.span(), scratch_);
  if (!ConstantTimeEqual(expected, fields.mac)) return CommandVerdict::kBadMac;
  if (!IsKnownKind(fields.kind)) return CommandVerdict::kUnknownKind;
  // Compare in double seconds: the difference of two int64 us values could overflow.
  const double skew_s = (static_cast<double>(fields.utime_us) - static_cast<double>(now_us)) * 1e-6;
  if (std::abs(skew_s) > options_.max_clock_skew_s) return CommandVerdict::kStale;
  if (CounterAhead(fields.counter, now_us)) return CommandVerdict::kCounterAhead;
  const auto it = counters_.find(fields.sender);
  if (it != counters_.end() && fields.counter <= it->second) return CommandVerdict::kReplayed;
  if (it == counters_.end()) {
    counters_.emplace(std::string(fields.sender), fields.counter);
  } else {
    it->second = fields.counter;
  }
  return CommandVerdict::kAccepted;
}

bool CommandAuthenticator::CounterAhead(int64_t counter, int64_t now_us) const {
  // In double: now_us + the window could overflow int64. Doubles are exact for integers up to
  // 2^53 (285 years in us), so the bound is exact for any realistic clock.
  return static_cast<double>(counter) >
         static_cast<double>(now_us) + options_.max_clock_skew_s * 1e6;
}

bool CommandAuthenticator::RestoreCounter(const std::string& sender, int64_t counter,
                                          int64_t now_us) {
  if (sender.empty() || sender.size() > kMaxCommandSenderBytes || counter <= 0 ||
      CounterAhead(counter, now_us)) {
    return false;
  }
  auto [it, inserted] = counters_.emplace(sender, counter);
  if (!inserted && counter > it->second) it->second = counter;
  return true;
}

}  // namespace canalid::drivers
