#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "drivers/lcm/log_reader.h"

namespace canalid::dashboard {

/// Plays an LCM log's events on an Asio loop at `speed` times the pace they were logged (0: as
/// fast as the loop takes them, in batches), handing each to `deliver`.  `finished` is called
/// once at the end with how it ended ("clean", or the damage and where).
class LogPlayback final {
 public:
  using Deliver = std::function<void(std::string_view channel, std::span<const std::uint8_t> data,
                                     std::int64_t utime)>;
  using Finished = std::function<void(std::int64_t events, const std::string& how)>;

  /// @throws std::runtime_error naming the path when it cannot be opened.
  LogPlayback(boost::asio::io_context& io, const std::string& path, double speed, Deliver deliver,
              Finished finished);
  void Start();
  void Cancel();

 private:
  void Step();

  static constexpr int kBatch = 2000;  ///< events per turn of the loop at speed 0
  drivers::LogReader reader_;
  boost::asio::steady_timer timer_;
  double speed_;
  Deliver deliver_;
  Finished finished_;
  drivers::LogEvent event_;
  bool pending_ = false;  ///< event_ is read and waits for its time
  std::int64_t first_utime_ = 0;
  std::chrono::steady_clock::time_point started_;
  std::int64_t events_ = 0;
  bool cancelled_ = false;
};

}  // namespace canalid::dashboard
