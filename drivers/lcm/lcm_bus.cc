#include "drivers/lcm/lcm_bus.h"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalid::drivers {

LcmBus::LcmBus(const std::string& url)
    : url_(url), reconnectable_(url.starts_with("tcpq:")), lcm_(std::make_unique<lcm::LCM>(url)) {
  if (!lcm_->good()) {
    throw std::runtime_error("lcm: cannot open url '" + url +
                             "' (empty means $LCM_DEFAULT_URL or udpm default; udpm needs a "
                             "multicast route, e.g. ip route add 224.0.0.0/4 dev lo)");
  }
}

LcmBus::~LcmBus() = default;

bool LcmBus::Publish(const std::string& channel, std::span<const uint8_t> data) noexcept {
  // A lost tcpq connection: liblcm would try to connect again on every publish, blocking for a
  // TCP connect each time; reconnecting is Reconnect()'s job.
  if (UsableFileno() < 0) return false;
  return lcm_->publish(channel, data.data(), static_cast<unsigned int>(data.size())) == 0;
}

int LcmBus::Subscribe(const std::string& channel_regex, RawHandler handler, int queue_capacity) {
  auto entry = std::make_unique<Entry>();
  entry->id = next_id_++;
  entry->handler = std::move(handler);
  entry->bus = this;
  entry->subscription = lcm_->subscribeFunction(channel_regex, &LcmBus::Dispatch, entry.get());
  if (entry->subscription == nullptr) {
    throw std::runtime_error("lcm: cannot subscribe to '" + channel_regex + "' on '" + url_ + "'");
  }
  entry->subscription->setQueueCapacity(std::max(queue_capacity, 1));
  entries_.push_back(std::move(entry));
  return entries_.back()->id;
}

void LcmBus::Unsubscribe(int id) noexcept {
  const auto it =
      std::find_if(entries_.begin(), entries_.end(), [id](const auto& e) { return e->id == id; });
  if (it == entries_.end()) return;
  lcm_->unsubscribe((*it)->subscription);
  entries_.erase(it);
}

void LcmBus::Dispatch(const lcm::ReceiveBuffer* buffer, const std::string& channel, Entry* entry) {
  // LCM calls this from C; nothing may escape.
  try {
    const std::span<const uint8_t> data(static_cast<const uint8_t*>(buffer->data),
                                        buffer->data_size);
    if (!entry->handler(channel, data)) entry->bus->failures_.fetch_add(1);
  } catch (...) {
    entry->bus->failures_.fetch_add(1);
  }
}

int LcmBus::Handle(double timeout_s) noexcept {
  const int timeout_ms =
      static_cast<int>(std::clamp(std::ceil(std::max(timeout_s, 0.0) * 1e3), 0.0, 2e9));
  if (UsableFileno() < 0) return -1;
  const int first = lcm_->handleTimeout(timeout_ms);
  if (first < 0) return -1;
  if (first == 0) return 0;
  int handled = 1;
  while (handled < 10000) {
    if (UsableFileno() < 0) return -1;
    const int rc = lcm_->handleTimeout(0);
    if (rc < 0) return -1;
    if (rc == 0) break;
    ++handled;
  }
  return handled;
}

int LcmBus::fileno() noexcept { return lcm_->getFileno(); }

int LcmBus::UsableFileno() noexcept {
  const int fd = lcm_->getFileno();
  if (fd >= 0 && reconnectable_) {
    // liblcm's tcpq reads a frame with blocking recv() calls until it is whole; on a non-blocking
    // socket a frame not yet fully arrived fails with EAGAIN and liblcm drops the connection.
    // A watcher of a dup() of this descriptor shares its file status flags (Boost.Asio's
    // async_wait sets O_NONBLOCK on the descriptor it waits on), so make it blocking again.
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0 && (flags & O_NONBLOCK) != 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    // liblcm may have replaced the socket (it connects again on its own): set the timeout on the
    // socket in use each time (one setsockopt per call).
    timeval timeout{};
    timeout.tv_sec = static_cast<time_t>(kTcpqReceiveTimeoutS);
    timeout.tv_usec = static_cast<suseconds_t>(
        (kTcpqReceiveTimeoutS - static_cast<double>(timeout.tv_sec)) * 1e6);
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  }
  return fd;
}

bool LcmBus::Reconnect(std::string* problem) noexcept {
  if (!reconnectable_) {
    if (problem != nullptr) *problem = "lcm: '" + url_ + "' is not a connection to reconnect";
    return false;
  }
  if (lcm_->getFileno() >= 0) return true;
  // liblcm's tcpq provider connects again, and subscribes every channel of this instance again,
  // when a subscription changes while it is disconnected; a probe subscription, removed at once,
  // does that with the public API. (Replacing the instance instead does not work: destroying one
  // whose connection is lost makes lcm_destroy connect again for each unsubscribe.) Blocking for
  // the TCP connect and the hub's 8-byte answer.
  try {
    lcm::Subscription* probe = lcm_->subscribeFunction(
        "CANALID_LCM_RECONNECT_PROBE",
        +[](const lcm::ReceiveBuffer*, const std::string&, LcmBus*) {}, this);
    if (probe == nullptr) {
      if (problem != nullptr) *problem = "lcm: cannot subscribe on '" + url_ + "'";
      return false;
    }
    lcm_->unsubscribe(probe);
    return true;
  } catch (const std::exception& e) {
    if (problem != nullptr) *problem = e.what();
    return false;
  }
}

}  // namespace canalid::drivers
