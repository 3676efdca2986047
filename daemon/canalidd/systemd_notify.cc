#include "daemon/canalidd/systemd_notify.h"

#include <systemd/sd-daemon.h>

namespace canalid::daemon {

void NotifyReady() { sd_notify(0, "READY=1"); }
void NotifyWatchdog() { sd_notify(0, "WATCHDOG=1"); }
void NotifyStatus(const std::string& status) { sd_notify(0, ("STATUS=" + status).c_str()); }
void NotifyStopping() { sd_notify(0, "STOPPING=1"); }
void NotifyReloading() { sd_notify(0, "RELOADING=1"); }

double WatchdogPeriodS() {
  uint64_t usec = 0;
  return sd_watchdog_enabled(0, &usec) > 0 ? static_cast<double>(usec) / 1e6 : 0.0;
}

}  // namespace canalid::daemon
