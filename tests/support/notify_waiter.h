#pragma once
// Waits for a condition that another thread's notifications make true (a poller's notify
// callback), with a bounded deadline and no sleeps.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>

namespace canalid::testing {

class NotifyWaiter {
 public:
  explicit NotifyWaiter(std::chrono::seconds timeout = std::chrono::seconds(30))
      : timeout_(timeout) {}
  /// The callback to hand to the notifying side.
  std::function<void()> Callback() {
    return [this] {
      std::lock_guard lock(mutex_);
      ++events_;
      cv_.notify_all();
    };
  }
  /// Re-checks `done` after every notification until it holds or the timeout passes.
  bool Until(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + timeout_;
    std::unique_lock lock(mutex_);
    while (true) {
      lock.unlock();
      if (done()) return true;
      lock.lock();
      const long seen = events_;
      if (!cv_.wait_until(lock, deadline, [&] { return events_ != seen; })) return done();
    }
  }

 private:
  std::chrono::seconds timeout_;
  std::mutex mutex_;
  std::condition_variable cv_;
  long events_ = 0;
};

}  // namespace canalid::testing
