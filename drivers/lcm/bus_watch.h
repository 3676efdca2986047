#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "drivers/lcm/bus.h"
#include "drivers/lcm/lcm_bus.h"

namespace canalid::drivers {

/// Handles the LCM bus's messages on the Asio loop when its descriptor is readable, and when the
/// connection is gone (tcpq hub lost) reconnects with a doubling backoff (0.1 s .. 5 s), counting
/// losses and reconnects for health.  A bus that is not an LcmBus (a fake in tests) is not
/// watched: the test pumps it.  Used by canalidd and by `canalid dashboard`.
class BusWatch final {
 public:
  /// Says what happened to the connection: `lost` true when it was lost (with the retry delay
  /// in the text), false when it is back.
  using ConnectionLog = std::function<void(bool lost, const std::string& text)>;

  /// `after_handle` runs after each Handle (the daemon logs rejected commands there); `stopping`
  /// ends the watch and the reconnects; `log` hears of losses and reconnects.
  BusWatch(boost::asio::io_context& io, Bus& bus, std::function<void()> after_handle,
           std::function<bool()> stopping, ConnectionLog log);
  void Start();
  void Cancel();
  int64_t losses() const { return losses_; }
  int64_t reconnects() const { return reconnects_; }

 private:
  void Watch();
  void Wait();
  // The LCM connection is gone (tcpq hub lost): counts it and retries with a doubling backoff.
  void OnLost(const std::string& why);
  // True when descriptors a and b name the same open socket (file).
  static bool SameSocket(int a, int b);

  static constexpr double kBackoffMinS = 0.1;
  static constexpr double kBackoffMaxS = 5.0;
  boost::asio::io_context& io_;
  Bus& bus_;
  LcmBus* lcm_bus_ = nullptr;  ///< bus_ when it is an LcmBus
  std::function<void()> after_handle_;
  std::function<bool()> stopping_;
  ConnectionLog log_;
  boost::asio::steady_timer retry_timer_;
  std::unique_ptr<boost::asio::posix::stream_descriptor> fd_;
  double backoff_s_ = kBackoffMinS;
  int64_t losses_ = 0;
  int64_t reconnects_ = 0;
};

}  // namespace canalid::drivers
