#include "daemon/canalidd/signal_watch.h"

#include <csignal>

#include "daemon/canalidd/log.h"

namespace canalid::daemon {

SignalWatch::SignalWatch(boost::asio::io_context& io, std::function<void()> on_stop,
                         std::function<bool()> on_hangup)
    : signals_(io, SIGINT, SIGTERM, SIGHUP),
      on_stop_(std::move(on_stop)),
      on_hangup_(std::move(on_hangup)) {}

void SignalWatch::Start() {
  signals_.async_wait([this](const boost::system::error_code& error, int signal) {
    if (error) return;
    if (signal == SIGHUP) {
      LogInfo("SIGHUP: checking the configuration");
      if (!on_hangup_()) Start();
      return;
    }
    LogInfo(signal == SIGTERM ? "SIGTERM: stopping" : "SIGINT: stopping");
    on_stop_();
  });
}

}  // namespace canalid::daemon
