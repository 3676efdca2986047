#include "drivers/lcm/log_reader.h"

#include "core/system/errno_text.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace canalid::drivers {
namespace {

constexpr std::size_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

std::uint64_t BigEndian(const std::uint8_t* bytes, int count) {
  std::uint64_t value = 0;
  for (int i = 0; i < count; ++i) value = (value << 8) | bytes[i];
  return value;
}

std::string Hex(std::uint32_t value) {
  std::ostringstream s;
  s << "0x" << std::hex << std::uppercase << value;
  return s.str();
}

}  // namespace

const char* LogEndName(LogEnd end) {
  switch (end) {
    case LogEnd::kReading:
      return "reading";
    case LogEnd::kClean:
      return "clean";
    case LogEnd::kTruncated:
      return "truncated";
    case LogEnd::kCorrupt:
      return "corrupt";
  }
  return "unknown";
}

LogReader::LogReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) throw std::runtime_error(path + ": cannot open: " + core::ErrnoText(errno));
  // Read in chunks into buffer_: stdio's own buffer would be one more copy.
  std::setvbuf(file_, nullptr, _IONBF, 0);
  if (std::fseek(file_, 0, SEEK_END) == 0) {
    const long size = std::ftell(file_);
    size_ = size > 0 ? static_cast<std::uint64_t>(size) : 0;
  }
  std::rewind(file_);
}

LogReader::~LogReader() {
  if (file_ != nullptr) std::fclose(file_);
}

bool LogReader::Fail(LogEnd end, std::string problem) {
  end_ = end;
  problem_ = std::move(problem);
  return false;
}

std::size_t LogReader::Available(std::size_t count) {
  if (buffered_ - next_ >= count) return count;
  // Keep the unread bytes, at the front; room for the event and at least one more chunk.
  const std::size_t kept = buffered_ - next_;
  if (kept > 0) std::memmove(buffer_.data(), buffer_.data() + next_, kept);
  next_ = 0;
  buffered_ = kept;
  const std::size_t room = std::max(count, kChunkBytes);
  if (buffer_.size() < room) buffer_.resize(room);
  while (buffered_ < count) {
    const std::size_t got =
        std::fread(buffer_.data() + buffered_, 1, buffer_.size() - buffered_, file_);
    buffered_ += got;
    if (got == 0) {  // the end of the file or an error
      if (std::ferror(file_) != 0) read_errno_ = errno != 0 ? errno : EIO;
      break;
    }
  }
  return std::min(count, buffered_);
}

std::string LogReader::ShortReadReason() const {
  if (read_errno_ != 0) return "read failed: " + core::ErrnoText(read_errno_);
  return "no bytes after byte " + std::to_string(position_ + (buffered_ - next_)) +
         ": the file is shorter than when it was opened (" + std::to_string(size_) + " bytes)";
}

bool LogReader::Next(LogEvent* event) {
  if (end_ != LogEnd::kReading) return false;
  const std::uint64_t start = position_;
  // Built only for a message: Next() runs once per event and does not allocate.
  auto at = [start] { return "byte " + std::to_string(start) + ": "; };
  const std::size_t got = Available(kHeaderBytes);
  const std::uint8_t* header = buffer_.data() + next_;
  // Fewer bytes than the file had when opened: it shrank since, or a read failed.
  const bool short_read = read_errno_ != 0 || position_ + got < size_;
  if (got == 0 && !short_read) {
    end_ = LogEnd::kClean;
    return false;
  }
  if (got >= 4) {
    const auto sync = static_cast<std::uint32_t>(BigEndian(header, 4));
    if (sync != kSyncWord) {
      return Fail(LogEnd::kCorrupt, at() + "not an LCM event (sync word " + Hex(sync) +
                                        ", expected " + Hex(kSyncWord) + ")");
    }
  }
  if (got < kHeaderBytes && short_read) return Fail(LogEnd::kTruncated, at() + ShortReadReason());
  if (got < kHeaderBytes) {
    return Fail(LogEnd::kTruncated, at() + "the log ends inside an event header (" +
                                        std::to_string(got) + " of " +
                                        std::to_string(kHeaderBytes) + " bytes)");
  }
  const auto event_number = static_cast<std::int64_t>(BigEndian(header + 4, 8));
  const auto utime = static_cast<std::int64_t>(BigEndian(header + 12, 8));
  const auto channel_length = static_cast<std::int32_t>(BigEndian(header + 20, 4));
  const auto data_length = static_cast<std::int32_t>(BigEndian(header + 24, 4));
  if (channel_length <= 0 || channel_length > kMaxChannelLength) {
    return Fail(LogEnd::kCorrupt, at() + "event " + std::to_string(event_number) +
                                      ": impossible channel length " +
                                      std::to_string(channel_length) + " (allowed 1.." +
                                      std::to_string(kMaxChannelLength) + ")");
  }
  if (data_length < 0) {
    return Fail(LogEnd::kCorrupt, at() + "event " + std::to_string(event_number) +
                                      ": negative data length " + std::to_string(data_length));
  }
  const std::uint64_t body =
      static_cast<std::uint64_t>(channel_length) + static_cast<std::uint64_t>(data_length);
  if (start + kHeaderBytes + body > size_) {
    return Fail(LogEnd::kTruncated, at() + "event " + std::to_string(event_number) + " needs " +
                                        std::to_string(kHeaderBytes + body) +
                                        " bytes, the log ends at byte " + std::to_string(size_));
  }
  const std::size_t whole = kHeaderBytes + static_cast<std::size_t>(body);
  if (Available(whole) < whole) {  // the file was longer when opened
    return Fail(LogEnd::kTruncated,
                at() + "event " + std::to_string(event_number) + ": " + ShortReadReason());
  }
  const std::uint8_t* bytes = buffer_.data() + next_ + kHeaderBytes;  // Available may move them
  next_ += whole;
  position_ = start + whole;
  event->event_number = event_number;
  event->utime = utime;
  event->offset = start;
  event->channel = std::string_view(reinterpret_cast<const char*>(bytes),
                                    static_cast<std::size_t>(channel_length));
  event->data =
      std::span<const std::uint8_t>(bytes + channel_length, static_cast<std::size_t>(data_length));
  return true;
}

}  // namespace canalid::drivers
