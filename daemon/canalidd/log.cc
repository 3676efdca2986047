#include "daemon/canalidd/log.h"

#include <unistd.h>

#include <atomic>
#include <string>

namespace canalid::daemon {
namespace {
std::atomic<int> g_level{static_cast<int>(LogLevel::kInfo)};
}

void SetLogLevel(LogLevel level) { g_level = static_cast<int>(level); }

void Log(LogLevel level, std::string_view message) {
  if (static_cast<int>(level) > g_level.load()) return;
  std::string line = "<" + std::to_string(static_cast<int>(level)) + ">canalidd: ";
  line.append(message);
  line.push_back('\n');
  // One write(2) per line keeps lines from different threads whole.
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line.data(), line.size());
}

}  // namespace canalid::daemon
