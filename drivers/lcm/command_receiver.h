#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>

#include "drivers/auth/command_auth.h"
#include "drivers/lcm/bus.h"

namespace canalid::drivers {

/// A command that passed verification, handed to the daemon.
struct AcceptedCommand {
  drivers::CommandKind kind = drivers::CommandKind::kStartExperiment;
  int64_t utime_us = 0;
  int64_t counter = 0;
  std::string sender;
  std::string reach;
  std::string argument;
};

/// Messages of the command channel that may wait for the loop; more are dropped by the bus. Each
/// is at most kMaxCommandMessageBytes once checked, but the transport may queue larger ones.
inline constexpr int kCommandQueueCapacity = 64;

/// Receives canalid.command_t on one channel of a Bus, verifies each message with a
/// drivers::CommandAuthenticator against the daemon clock `now_us()`, counts every verdict and
/// calls `on_accepted` for accepted ones. Bytes are checked with CommandWireIsBounded before
/// lcm-gen's decoder sees them (no allocation from a length field of an unauthenticated message);
/// those that fail it, or do not decode as command_t, count as malformed. The channel name is part
/// of the signed bytes (drivers::CommandFields::channel). Never throws from the bus handler: an
/// exception from `on_accepted`, the clock or the MAC computation (an OpenSSL failure) is caught
/// and counted in callback_failures(). Runs on the Bus's thread; not thread-safe.
class CommandReceiver final {
 public:
  using Clock = std::function<int64_t()>;
  using Callback = std::function<void(const AcceptedCommand&)>;

  /// Subscribes to `channel` (an exact name, not a pattern). `authenticator` must outlive this.
  /// @throws std::runtime_error when the subscription cannot be made.
  CommandReceiver(Bus& bus, const std::string& channel,
                  drivers::CommandAuthenticator& authenticator, Clock now_us, Callback on_accepted);
  ~CommandReceiver();
  CommandReceiver(const CommandReceiver&) = delete;
  CommandReceiver& operator=(const CommandReceiver&) = delete;

  int64_t count(drivers::CommandVerdict verdict) const {
    return counts_[static_cast<std::size_t>(verdict)];
  }
  /// All messages that were not accepted.
  int64_t rejected() const;
  int64_t callback_failures() const { return callback_failures_; }

 private:
  void Receive(std::span<const uint8_t> data) noexcept;

  Bus& bus_;
  std::string channel_;
  drivers::CommandAuthenticator& authenticator_;
  Clock now_us_;
  Callback on_accepted_;
  int subscription_ = 0;
  std::array<int64_t, drivers::kNumCommandVerdicts> counts_{};
  int64_t callback_failures_ = 0;
};

}  // namespace canalid::drivers
