#pragma once
#include <string_view>

namespace canalid::daemon {

enum class LogLevel { kError = 3, kWarning = 4, kInfo = 6, kDebug = 7 };

/// Lines on stderr with a syslog priority prefix ("<6>"), which journald turns into priorities.
/// Thread-safe (one write per line).
void SetLogLevel(LogLevel level);
void Log(LogLevel level, std::string_view message);
inline void LogError(std::string_view m) { Log(LogLevel::kError, m); }
inline void LogWarning(std::string_view m) { Log(LogLevel::kWarning, m); }
inline void LogInfo(std::string_view m) { Log(LogLevel::kInfo, m); }
inline void LogDebug(std::string_view m) { Log(LogLevel::kDebug, m); }

}  // namespace canalid::daemon
