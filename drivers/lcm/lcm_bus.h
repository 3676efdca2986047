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
/// "file:///path/log?mode=w" (write a log), "file:///path/log?speed=0" (read one, lossless) or
/// "tcpq://HOST:PORT" (through an LCM TCP hub).
///
/// tcpq: liblcm's provider closes its socket when the hub goes away or a read fails and then
/// reports fileno -1; lcm_handle_timeout() would FD_SET(-1) and select() on it, which glibc's
/// fortified FD_SET aborts. So Handle() and Publish() never call into LCM while fileno() < 0
/// (they return -1 / false: the connection is lost), and Reconnect() has liblcm connect again
/// (the owner retries with a backoff). A receive timeout (kTcpqReceiveTimeoutS) is set on
/// the tcpq socket, so a hub that stops in the middle of a message cannot block the caller's loop
/// in liblcm's blocking recv() for longer; the connection is then dropped. The socket is kept in
/// blocking mode (a watcher's O_NONBLOCK on a dup made liblcm drop the connection on any frame that
/// had not fully arrived, e.g. a large message).
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

  /// The URL this bus was opened with.
  const std::string& url() const { return url_; }
  /// True for connection-based transports (tcpq) that can be lost and reconnected; udpm, memq and
  /// file are not (a file:// log must not be reopened: that would truncate it).
  bool reconnectable() const { return reconnectable_; }
  /// For a lost tcpq connection: has liblcm connect again and subscribe every handler again
  /// (blocking for the TCP connect and the hub's answer). False, with the reason in `problem`,
  /// for a bus that is not reconnectable. True when connected already or an attempt was made:
  /// check fileno() >= 0 for the outcome.
  bool Reconnect(std::string* problem) noexcept;

  static constexpr double kTcpqReceiveTimeoutS = 1.0;

 private:
  struct Entry {
    int id = 0;
    lcm::Subscription* subscription = nullptr;
    RawHandler handler;
    LcmBus* bus = nullptr;
  };
  static void Dispatch(const lcm::ReceiveBuffer* buffer, const std::string& channel, Entry* entry);
  // LCM's descriptor when it may be handed to LCM (>= 0); -1 when the connection is lost.
  int UsableFileno() noexcept;

  std::string url_;
  bool reconnectable_ = false;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Entry>> entries_;
  int next_id_ = 1;
  std::atomic<int64_t> failures_{0};
};

}  // namespace canalid::drivers
