#pragma once
#include <string_view>

#include "daemon/config/daemon_config.h"

namespace canalid::daemon {

using config::LogLevel;

/// Lines on stderr with the syslog priority of their level as prefix ("<6>" for info), which
/// journald turns into priorities; lines above the level set (the configuration's log_level) are
/// dropped. Thread-safe (one write per line).
void SetLogLevel(LogLevel level);
void Log(LogLevel level, std::string_view message);
inline void LogError(std::string_view m) { Log(LogLevel::kError, m); }
inline void LogWarning(std::string_view m) { Log(LogLevel::kWarn, m); }
inline void LogInfo(std::string_view m) { Log(LogLevel::kInfo, m); }
inline void LogDebug(std::string_view m) { Log(LogLevel::kDebug, m); }

}  // namespace canalid::daemon
