#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "drivers/lcm/bus.h"

namespace lcm {
class LCM;
class ReceiveBuffer;
class Subscription;
}  // namespace lcm

namespace canalid::drivers {

/// Bus over lcm::LCM. URLs: "" (LCM's default: $LCM_DEFAULT_URL, else
/// udpm://239.255.76.67:7667?ttl=0), "udpm://GROUP:PORT?ttl=N", "memq://" (in process),
/// "file:///path/log?mode=w" (write a log) or "file:///path/log?speed=0" (read one, lossless).
class LcmBus final : public Bus {
 public:
  /// @throws std::runtime_error naming the URL when LCM cannot be created (bad URL, no multicast
  ///   route for udpm, unreadable log).
  explicit LcmBus(const std::string& url);
  ~LcmBus() override;
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  bool Publish(const std::string& channel, std::span<const uint8_t> data) noexcept override;
  int Subscribe(const std::string& channel_regex, RawHandler handler,
                int queue_capacity = 1000) override;
  void Unsubscribe(int id) noexcept override;
  int Handle(double timeout_s) noexcept override;
  int64_t handler_failures() const noexcept override { return failures_.load(); }

  /// File descriptor that becomes readable when a message is waiting (for an Asio
  /// posix::stream_descriptor, so the io_context calls Handle(0) only when there is work).
  int fileno() noexcept;

 private:
  struct Entry {
    int id = 0;
    lcm::Subscription* subscription = nullptr;
    RawHandler handler;
    LcmBus* bus = nullptr;
  };
  static void Dispatch(const lcm::ReceiveBuffer* buffer, const std::string& channel, Entry* entry);

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Entry>> entries_;
  int next_id_ = 1;
  std::atomic<int64_t> failures_{0};
};

}  // namespace canalid::drivers
