#include "drivers/lcm/bus_watch.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "core/system/errno_text.h"

namespace canalid::drivers {

BusWatch::BusWatch(boost::asio::io_context& io, Bus& bus, std::function<void()> after_handle,
                   std::function<bool()> stopping, ConnectionLog log)
    : io_(io),
      bus_(bus),
      after_handle_(std::move(after_handle)),
      stopping_(std::move(stopping)),
      log_(std::move(log)),
      retry_timer_(io) {}

void BusWatch::Start() {
  lcm_bus_ = dynamic_cast<LcmBus*>(&bus_);
  if (lcm_bus_ == nullptr) return;  // a fake bus in tests is pumped by the test
  Watch();
}

void BusWatch::Cancel() {
  if (fd_) fd_->cancel();
  retry_timer_.cancel();
}

// Watches a duplicate of LCM's descriptor, so Asio never closes LCM's own. LCM's tcpq provider
// may close its socket (hub gone, an unreadable message) and leave fileno -1, or reconnect on its
// own onto another socket: the watched duplicate then no longer names LCM's socket (SameSocket),
// and Handle() with fileno -1 would make liblcm select() on fd -1 and abort (LcmBus::Handle
// refuses that instead).
void BusWatch::Watch() {
  const int fd = lcm_bus_->fileno();
  const int copy = fd < 0 ? -1 : ::dup(fd);
  if (copy < 0) {
    OnLost(fd < 0 ? "no connection (fileno -1)" : std::string("dup: ") + core::ErrnoText(errno));
    return;
  }
  fd_ = std::make_unique<boost::asio::posix::stream_descriptor>(io_, copy);
  Wait();
}

void BusWatch::Wait() {
  fd_->async_wait(boost::asio::posix::stream_descriptor::wait_read,
                  [this](const boost::system::error_code& error) {
                    if (error) return;
                    const int handled = bus_.Handle(0.0);
                    after_handle_();
                    if (stopping_()) return;
                    if (lcm_bus_->reconnectable()) {
                      const int fd = lcm_bus_->fileno();
                      if (handled < 0 || fd < 0 || !SameSocket(fd_->native_handle(), fd)) {
                        OnLost(handled < 0 ? "receive failed" : "connection closed");
                        return;
                      }
                    }
                    Wait();
                  });
}

bool BusWatch::SameSocket(int a, int b) {
  struct stat sa {
  }, sb{};
  return ::fstat(a, &sa) == 0 && ::fstat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

void BusWatch::OnLost(const std::string& why) {
  fd_.reset();
  ++losses_;
  const double delay_s = backoff_s_;
  backoff_s_ = std::min(backoff_s_ * 2.0, kBackoffMaxS);
  log_(true, "LCM bus " + lcm_bus_->url() + " lost (" + why + "); reconnecting in " +
                 std::to_string(delay_s) + " s");
  retry_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(delay_s)));
  retry_timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || stopping_()) return;
    std::string problem;
    if (!lcm_bus_->Reconnect(&problem) || lcm_bus_->fileno() < 0) {
      OnLost(problem.empty() ? "no connection (fileno -1)" : problem);
      return;
    }
    ++reconnects_;
    backoff_s_ = kBackoffMinS;
    log_(false, "LCM bus " + lcm_bus_->url() + " reconnected");
    Watch();
  });
}

}  // namespace canalid::drivers
