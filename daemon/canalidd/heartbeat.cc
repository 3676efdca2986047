#include "daemon/canalidd/heartbeat.h"

#include "daemon/canalidd/clock.h"

namespace canalid::daemon {

Heartbeat::Heartbeat(boost::asio::io_context& io, drivers::PlcPoller& poller, int channel,
                     double period_s, std::function<bool()> stopping)
    : timer_(io),
      poller_(poller),
      channel_(channel),
      period_s_(period_s),
      stopping_(std::move(stopping)) {}

void Heartbeat::Start() {
  if (channel_ < 0) return;
  timer_.expires_after(Seconds(period_s_));
  timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || stopping_()) return;
    ++value_;
    poller_.RequestWrite(channel_, static_cast<double>(value_));
    Start();
  });
}

}  // namespace canalid::daemon
