#pragma once
#include <string>

namespace canalid::daemon {

/// sd_notify(3) messages; no-ops when not started by systemd (NOTIFY_SOCKET unset).
void NotifyReady();
void NotifyWatchdog();
void NotifyStatus(const std::string& status);
void NotifyStopping();
void NotifyReloading();
/// The watchdog period systemd expects (WatchdogSec), 0 when none.
double WatchdogPeriodS();

}  // namespace canalid::daemon
