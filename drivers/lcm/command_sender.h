#pragma once
#include <cstdint>
#include <span>
#include <string_view>

#include "canalid/command_t.hpp"
#include "drivers/auth/command_auth.h"

namespace canalid::drivers {

/// A canalid.command_t carrying `fields` (fields.mac is ignored) and their HMAC-SHA256 under
/// `key` (drivers::SignCommand), ready to publish on fields.channel (which the MAC covers; the
/// channel itself is not a field of the message).
canalid::command_t BuildSignedCommand(std::span<const uint8_t> key,
                                      const drivers::CommandFields& fields);

/// The signed fields of `message` received on `channel`, its MAC included: the inverse of
/// BuildSignedCommand.  The views point into `message` and `channel`, which must outlive them.
drivers::CommandFields CommandFieldsOf(const canalid::command_t& message, std::string_view channel);

}  // namespace canalid::drivers
