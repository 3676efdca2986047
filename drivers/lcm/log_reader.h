#pragma once
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace canalid::drivers {

/// One event of an LCM log; `channel` and `data` stay valid until the next LogReader::Next().
struct LogEvent {
  std::int64_t event_number = 0;
  std::int64_t utime = 0;    ///< when the logger received it, us since the Unix epoch
  std::uint64_t offset = 0;  ///< byte offset of the event's sync word in the file
  std::string_view channel;
  std::span<const std::uint8_t> data;
};

/// How reading ended.
enum class LogEnd {
  kReading,    ///< not at the end yet
  kClean,      ///< the file ends after a whole event
  kTruncated,  ///< the last event is cut short (a log still being written, or a killed logger)
  kCorrupt,    ///< bytes that are not an event (bad sync word or impossible lengths)
};

/// Reads an LCM event log (the format lcm-logger and LCM's file:// provider write: per event the
/// big-endian sync word 0xEDA1DA01, int64 event number, int64 timestamp, int32 channel length,
/// int32 data length, then the channel and the data) in order, losslessly, with the byte offset
/// of every event, and stops at the first damage, saying where and what.  The file is read in
/// chunks of kChunkBytes into one buffer and events are returned in place: reading does not
/// allocate once the largest event has been seen.
class LogReader final {
 public:
  /// @throws std::runtime_error naming the path when it cannot be opened.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  /// The next event; false at the end of the log or at damage (see end() and problem()).
  bool Next(LogEvent* event);

  LogEnd end() const { return end_; }
  /// What is wrong and where ("byte 1234: ..."), when end() is kTruncated or kCorrupt.
  const std::string& problem() const { return problem_; }
  /// Offset of the first byte not read as part of a whole event.
  std::uint64_t position() const { return position_; }
  std::uint64_t size_bytes() const { return size_; }
  const std::string& path() const { return path_; }

  static constexpr std::uint32_t kSyncWord = 0xEDA1DA01U;
  static constexpr std::int32_t kMaxChannelLength = 255;
  static constexpr std::size_t kChunkBytes = std::size_t{1} << 20;

 private:
  bool Fail(LogEnd end, std::string problem);
  /// Why the file gave fewer bytes than it had when opened: the failed read's errno, or that it
  /// is shorter now.
  std::string ShortReadReason() const;
  /// Makes `count` bytes from the next unread one available in buffer_ (reading more of the
  /// file); returns how many are (fewer at the end of the file or on a read error).
  std::size_t Available(std::size_t count);

  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t position_ = 0;
  LogEnd end_ = LogEnd::kReading;
  std::string problem_;
  std::vector<std::uint8_t> buffer_;
  std::size_t next_ = 0;      // the next unread byte in buffer_
  std::size_t buffered_ = 0;  // bytes of buffer_ read from the file
  int read_errno_ = 0;        // errno of the read that failed (0: none failed)
};

const char* LogEndName(LogEnd end);

}  // namespace canalid::drivers
