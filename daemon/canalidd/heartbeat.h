#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <cstdint>
#include <functional>

#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// The heartbeat register a PLC's watchdog watches: every `period_s` the next value of a 16-bit
/// counter is queued as a write on `channel` of the poller.  Runs on the Asio loop.
class Heartbeat final {
 public:
  /// `channel` < 0: no heartbeat (Start does nothing).  `stopping` ends the beat at the next tick.
  Heartbeat(boost::asio::io_context& io, drivers::PlcPoller& poller, int channel, double period_s,
            std::function<bool()> stopping);
  void Start();
  void Cancel() { timer_.cancel(); }

 private:
  boost::asio::steady_timer timer_;
  drivers::PlcPoller& poller_;
  int channel_;
  double period_s_;
  std::function<bool()> stopping_;
  std::uint16_t value_ = 0;
};

}  // namespace canalid::daemon
