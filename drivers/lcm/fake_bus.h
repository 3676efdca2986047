#pragma once
#include <cstdint>
#include <deque>
#include <regex>
#include <string>
#include <vector>

#include "drivers/lcm/bus.h"

namespace canalid::drivers {

/// In-memory Bus for tests of code above the bus: every publish is recorded (published()) and
/// queued; Handle() delivers the queue to subscribers whose regex fully matches the channel, in
/// publish order, honouring each subscription's queue capacity (older messages kept, newer
/// dropped, as LCM does). Not thread-safe.
class FakeBus final : public Bus {
 public:
  struct Message {
    std::string channel;
    std::vector<uint8_t> data;
  };

  bool Publish(const std::string& channel, std::span<const uint8_t> data) noexcept override;
  int Subscribe(const std::string& channel_regex, RawHandler handler,
                int queue_capacity = 1000) override;
  void Unsubscribe(int id) noexcept override;
  int Handle(double timeout_s) noexcept override;
  int64_t handler_failures() const noexcept override { return failures_; }

  const std::vector<Message>& published() const { return published_; }
  /// Makes the next Publish calls fail (return false), e.g. to test error counting.
  void set_publish_fails(bool fails) { publish_fails_ = fails; }
  int64_t dropped() const { return dropped_; }

 private:
  struct Entry {
    int id = 0;
    std::regex pattern;
    RawHandler handler;
    int capacity = 0;
    std::deque<std::size_t> pending;  // indices into published_
  };

  std::vector<Message> published_;
  std::vector<Entry> entries_;
  int next_id_ = 1;
  int64_t failures_ = 0;
  int64_t dropped_ = 0;
  bool publish_fails_ = false;
};

}  // namespace canalid::drivers
