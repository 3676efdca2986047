#include "drivers/lcm/command_sender.h"

#include <string>

namespace canalid::drivers {

canalid::command_t BuildSignedCommand(std::span<const uint8_t> key,
                                      const drivers::CommandFields& fields) {
  canalid::command_t message;
  message.utime = fields.utime_us;
  message.counter = fields.counter;
  message.sender = std::string(fields.sender);
  message.kind = fields.kind;
  message.reach = std::string(fields.reach);
  message.argument = std::string(fields.argument);
  const drivers::Sha256Digest mac = drivers::SignCommand(key, fields);
  message.hmac.assign(mac.begin(), mac.end());
  message.hmac_size = static_cast<int32_t>(message.hmac.size());
  return message;
}

drivers::CommandFields CommandFieldsOf(const canalid::command_t& message,
                                       std::string_view channel) {
  drivers::CommandFields fields;
  fields.channel = channel;
  fields.utime_us = message.utime;
  fields.counter = message.counter;
  fields.sender = message.sender;
  fields.kind = message.kind;
  fields.reach = message.reach;
  fields.argument = message.argument;
  fields.mac = std::span<const uint8_t>(message.hmac.data(), message.hmac.size());
  return fields;
}

}  // namespace canalid::drivers
