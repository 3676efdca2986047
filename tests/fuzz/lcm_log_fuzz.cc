// LCM event logs as `canalid replay`, `canalid export` and `canalid report` read them
// (drivers/lcm/log_reader.h, log_messages.h): the bytes are the contents of a log file (an
// in-memory file, memfd, opened by path as the programs open a log), read event by event with
// LogReader and scanned with ScanCanalidLog, whose configuration messages are parsed as `canalid
// replay` parses them (ParseDaemonConfig).  Properties: the reader never reads past the file, an
// event lies inside the file after the previous one, a clean end is at the end of the file, and
// the scan stops where the reader does.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "daemon/config/config_loader.h"
#include "drivers/lcm/log_messages.h"
#include "drivers/lcm/log_reader.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using canalid::fuzz::Check;
namespace drivers = canalid::drivers;

// The log file: one memfd for the process, rewritten for every input.
const std::string& WriteLog(const uint8_t* data, std::size_t size) {
  static const int kLogFd = memfd_create("canalid-fuzz-log", 0);
  static const std::string kLogPath = "/proc/self/fd/" + std::to_string(kLogFd);
  Check(kLogFd >= 0, "memfd_create works");
  Check(ftruncate(kLogFd, 0) == 0, "the log file can be emptied");
  std::size_t written = 0;
  while (written < size) {
    const ssize_t n = pwrite(kLogFd, data + written, size - written, static_cast<off_t>(written));
    Check(n > 0, "the log file can be written");
    written += static_cast<std::size_t>(n);
  }
  return kLogPath;
}

class Visitor final : public drivers::LogMessageVisitor {
 public:
  void OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) override {
    Check(event.channel.ends_with("CONFIG"), "a configuration comes on a CONFIG channel");
    try {
      canalid::daemon::ParseDaemonConfig(config.text, "logged.toml");
    } catch (const canalid::daemon::ConfigError&) {
      // `canalid replay` reports it as an invalid logged configuration.
    }
  }
  void OnSample(const std::string& plc, const canalid::sample_t& sample,
                const drivers::LogEvent& event) override {
    Check(event.channel.ends_with(plc), "the PLC name is the channel's suffix");
    Check(sample.num_channels >= 0, "a decoded sample has a channel count");
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = WriteLog(data, size);
  {
    drivers::LogReader reader(path);
    Check(reader.size_bytes() == size, "the reader sees the whole file");
    drivers::LogEvent event;
    std::uint64_t previous_end = 0;
    while (reader.Next(&event)) {
      Check(event.offset == previous_end, "events follow one another");
      Check(reader.position() <= size, "an event lies inside the file");
      Check(!event.channel.empty(), "an event has a channel");
      previous_end = reader.position();
    }
    Check(reader.end() != drivers::LogEnd::kReading, "reading ends");
    Check(reader.position() == previous_end, "the position is the end of the last whole event");
    Check((reader.end() == drivers::LogEnd::kClean) == (reader.position() == size),
          "a clean end is the end of the file");
    Check((reader.end() == drivers::LogEnd::kClean) == reader.problem().empty(),
          "damage is described");
  }
  Visitor visitor;
  const drivers::LogScanResult result = ScanCanalidLog(path, {}, visitor);
  Check(result.end != drivers::LogEnd::kReading, "the scan ends");
  Check(result.bytes <= size, "the scan stays inside the file");
  Check(result.samples + result.skipped_events <= result.events, "events add up");
  Check((result.end == drivers::LogEnd::kClean) == result.problem.empty(), "damage is described");
  return 0;
}
