#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <functional>

namespace canalid::daemon {

/// SIGTERM, SIGINT and SIGHUP on the Asio loop (caught from construction on).  SIGTERM/SIGINT
/// call `on_stop` once and end the watch; SIGHUP calls `on_hangup`, which returns true when the
/// daemon stops to reload (the watch ends) and false to carry on (the watch goes on).
class SignalWatch final {
 public:
  SignalWatch(boost::asio::io_context& io, std::function<void()> on_stop,
              std::function<bool()> on_hangup);
  void Start();
  void Cancel() { signals_.cancel(); }

 private:
  boost::asio::signal_set signals_;
  std::function<void()> on_stop_;
  std::function<bool()> on_hangup_;
};

}  // namespace canalid::daemon
