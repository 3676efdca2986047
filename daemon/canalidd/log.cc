#include "daemon/canalidd/log.h"

#include <unistd.h>

#include <atomic>
#include <string>

namespace canalid::daemon {
namespace {

// syslog(3) priorities: LOG_ERR, LOG_WARNING, LOG_INFO, LOG_DEBUG.
int SyslogPriority(LogLevel level) {
  switch (level) {
    case LogLevel::kError:
      return 3;
    case LogLevel::kWarn:
      return 4;
    case LogLevel::kInfo:
      return 6;
    case LogLevel::kDebug:
      return 7;
  }
  return 6;
}

std::atomic<int> g_priority{SyslogPriority(LogLevel::kInfo)};

}  // namespace

void SetLogLevel(LogLevel level) { g_priority = SyslogPriority(level); }

void Log(LogLevel level, std::string_view message) {
  const int priority = SyslogPriority(level);
  if (priority > g_priority.load()) return;
  std::string line = "<" + std::to_string(priority) + ">canalidd: ";
  line.append(message);
  line.push_back('\n');
  // One write(2) per line keeps lines from different threads whole.
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line.data(), line.size());
}

}  // namespace canalid::daemon
