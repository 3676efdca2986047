#include "drivers/lcm/command_receiver.h"

#include <regex>

#include "canalid/command_t.hpp"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/command_wire.h"

namespace canalid::drivers {

CommandReceiver::CommandReceiver(Bus& bus, const std::string& channel,
                                 drivers::CommandAuthenticator& authenticator, Clock now_us,
                                 Callback on_accepted)
    : bus_(bus),
      channel_(channel),
      authenticator_(authenticator),
      now_us_(std::move(now_us)),
      on_accepted_(std::move(on_accepted)) {
  // The bus matches a regex; escape the channel so names with '.' match only themselves.
  static const std::regex kSpecial(R"([.^$|()\[\]{}*+?\\])");
  const std::string pattern = std::regex_replace(channel, kSpecial, R"(\$&)");
  subscription_ = bus_.Subscribe(
      pattern,
      [this](const std::string&, std::span<const uint8_t> d) {
        Receive(d);
        return true;  // rejected commands are counted here, not as bus handler failures
      },
      kCommandQueueCapacity);
}

CommandReceiver::~CommandReceiver() { bus_.Unsubscribe(subscription_); }

int64_t CommandReceiver::rejected() const {
  int64_t total = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    if (i != static_cast<std::size_t>(drivers::CommandVerdict::kAccepted)) total += counts_[i];
  }
  return total;
}

void CommandReceiver::Receive(std::span<const uint8_t> data) noexcept {
  auto verdict = drivers::CommandVerdict::kMalformed;
  // Before lcm-gen's decode, which would allocate what hmac_size says (CommandWireIsBounded).
  if (!CommandWireIsBounded(data)) {
    ++counts_[static_cast<std::size_t>(verdict)];
    return;
  }
  try {
    canalid::command_t message;
    if (DecodeMessage(data, message) && message.hmac_size >= 0 &&
        static_cast<std::size_t>(message.hmac_size) == message.hmac.size()) {
      const drivers::CommandFields fields = CommandFieldsOf(message, channel_);
      verdict = authenticator_.Verify(fields, now_us_());
      if (verdict == drivers::CommandVerdict::kAccepted) {
        ++counts_[static_cast<std::size_t>(verdict)];
        AcceptedCommand command{static_cast<drivers::CommandKind>(message.kind),
                                message.utime,
                                message.counter,
                                message.sender,
                                message.reach,
                                message.argument};
        on_accepted_(command);
        return;
      }
    }
  } catch (...) {
    // A throwing clock, callback or MAC computation (an accepted command is already counted as
    // accepted).
    ++callback_failures_;
    return;
  }
  ++counts_[static_cast<std::size_t>(verdict)];
}

}  // namespace canalid::drivers
