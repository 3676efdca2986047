#pragma once
#include <cstdint>
#include <exception>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <canalid/lcm_shapes.hpp>

namespace canalid::drivers {

/// Receives one raw message: the channel it came on and its bytes (valid during the call only).
/// Returns false when the message was rejected (e.g. it did not decode); the bus counts those.
using RawHandler = std::function<bool(const std::string& channel, std::span<const uint8_t> data)>;

/// Publish/subscribe bus, made to be faked (cf. Drake's DrakeLcmInterface). Implemented over LCM
/// by LcmBus and in memory by FakeBus.
///
/// Threading: one thread publishes, subscribes and calls Handle() (the daemon's Asio thread);
/// handlers run inside Handle() on that thread. Publish and Handle never throw; an exception
/// thrown by a handler is caught and counted in handler_failures(), as is a handler returning
/// false.
class Bus {
 public:
  virtual ~Bus() = default;

  /// Sends `data` on `channel`. False when the transport refused it (counted by the caller).
  virtual bool Publish(const std::string& channel, std::span<const uint8_t> data) noexcept = 0;

  /// Delivers messages whose channel fully matches the POSIX extended regex `channel_regex` to
  /// `handler`. Up to `queue_capacity` messages wait for Handle() before new ones are dropped
  /// (LCM's default of 30 loses data at 1 kHz bursts). Returns an id for Unsubscribe.
  /// @throws std::runtime_error when the subscription cannot be made (start-up only).
  virtual int Subscribe(const std::string& channel_regex, RawHandler handler,
                        int queue_capacity = 1000) = 0;
  virtual void Unsubscribe(int id) noexcept = 0;

  /// Waits up to `timeout_s` for a message, then dispatches it and any others already queued
  /// (at most 10000 per call). Returns the number dispatched (0 on timeout), or -1 on a transport
  /// error.
  virtual int Handle(double timeout_s) noexcept = 0;

  /// Handler exceptions and rejected messages since construction.
  virtual int64_t handler_failures() const noexcept = 0;
};

/// Encodes an lcm-gen message into `buffer` (grown as needed, reused across calls so steady
/// publishing does not allocate) and publishes it. False if encoding or publishing fails.
template <class Message>
bool PublishMessage(Bus& bus, const std::string& channel, const Message& message,
                    std::vector<uint8_t>& buffer) noexcept {
  try {
    const int size = message.getEncodedSize();
    if (size < 0) return false;
    if (buffer.size() < static_cast<std::size_t>(size))
      buffer.resize(static_cast<std::size_t>(size));
    if (message.encode(buffer.data(), 0, size) != size) return false;
    return bus.Publish(channel,
                       std::span<const uint8_t>(buffer.data(), static_cast<std::size_t>(size)));
  } catch (...) {
    return false;  // allocation failure while growing the buffer
  }
}

/// Decodes `data` as one lcm-gen Message: true when the bytes are exactly one message.
/// Before decoding, the bytes are walked against the type's encoding (lcm_shapes.hpp, generated
/// from the .lcm files): lcm-gen sizes an array from its count field before it reads the bytes,
/// so a message of 100 bytes claiming 2^31 elements would allocate tens of GB.  After the walk no
/// array has more elements than the message has bytes (a decode allocates at most a few times
/// the message: a std::string element is 32 bytes for at least 5 encoded).  Anything lcm-gen's
/// decoders still throw (an allocation failure) is malformed too: false, never an exception.
template <class Message>
bool DecodeMessage(std::span<const uint8_t> data, Message& message) noexcept {
  if (data.size() > static_cast<std::size_t>(INT32_MAX)) return false;
  if (!canalid::lcm_shapes::Fits(static_cast<const Message*>(nullptr), data.data(), data.size())) {
    return false;
  }
  const int size = static_cast<int>(data.size());
  try {
    return message.decode(data.data(), 0, size) == size;
  } catch (const std::exception&) {
    return false;
  }
}

/// Subscribes `handler(const std::string& channel, const Message&)` to `channel_regex`; messages
/// that do not decode as Message are rejected (counted in handler_failures) and not passed on.
template <class Message, class F>
int SubscribeMessage(Bus& bus, const std::string& channel_regex, F handler,
                     int queue_capacity = 1000) {
  return bus.Subscribe(
      channel_regex,
      [handler = std::move(handler)](const std::string& channel,
                                     std::span<const uint8_t> data) mutable -> bool {
        Message message;
        if (!DecodeMessage(data, message)) return false;
        handler(channel, message);
        return true;
      },
      queue_capacity);
}

}  // namespace canalid::drivers
