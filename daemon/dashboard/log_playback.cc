#include "daemon/dashboard/log_playback.h"

#include <algorithm>
#include <chrono>

namespace canalid::dashboard {

LogPlayback::LogPlayback(boost::asio::io_context& io, const std::string& path, double speed,
                         Deliver deliver, Finished finished)
    : reader_(path),
      timer_(io),
      speed_(speed),
      deliver_(std::move(deliver)),
      finished_(std::move(finished)) {}

void LogPlayback::Start() {
  started_ = std::chrono::steady_clock::now();
  boost::asio::post(timer_.get_executor(), [this] { Step(); });
}

void LogPlayback::Cancel() {
  cancelled_ = true;
  timer_.cancel();
}

// Delivers every event that is due (at speed 0: a batch), then waits for the next one's time.
void LogPlayback::Step() {
  if (cancelled_) return;
  for (int delivered = 0; delivered < kBatch; ++delivered) {
    if (!pending_) {
      if (!reader_.Next(&event_)) {
        const std::string how =
            reader_.end() == drivers::LogEnd::kClean
                ? "clean"
                : std::string(drivers::LogEndName(reader_.end())) + ": " + reader_.problem();
        finished_(events_, how);
        return;
      }
      pending_ = true;
      if (events_ == 0) first_utime_ = event_.utime;
    }
    if (speed_ > 0.0) {
      // In doubles and clamped to a year: log times may be anything.
      const double wait_s = std::clamp(
          (static_cast<double>(event_.utime) - static_cast<double>(first_utime_)) * 1e-6 / speed_,
          0.0, 3.2e7);
      const auto due = started_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(wait_s));
      if (due > std::chrono::steady_clock::now()) {
        timer_.expires_at(due);
        timer_.async_wait([this](const boost::system::error_code& error) {
          if (!error) Step();
        });
        return;
      }
    }
    pending_ = false;
    ++events_;
    deliver_(event_.channel, event_.data, event_.utime);
  }
  boost::asio::post(timer_.get_executor(), [this] { Step(); });
}

}  // namespace canalid::dashboard
