#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include "daemon/canalidd/daemon_plan.h"

namespace canalid::daemon {

/// A problem that stops canalidd from starting (or a reload from taking effect): a bad key file,
/// an unusable state directory, a bus or driver the plan names that cannot be opened. canalidd
/// exits 78 (EX_CONFIG) on it, so systemd's RestartPreventExitStatus=78 ends a restart loop.
class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What CheckStartup found that is not an error (printed by --check-config).
struct StartupNotes {
  std::vector<std::string> notes;
};

/// The checks of the files a plan names, shared by `canalidd --check-config` and the start of the
/// daemon, so a file the check accepts is one the daemon accepts:
/// - commands enabled: the key file is read and validated with ReadKeyFile (permissions, format)
///   and the key wiped at once;
/// - the state directory: when it exists it must be a directory this process can create files in
///   (a file is created and removed in it). When it does not exist, `for_start` makes that an error
///   (the daemon would find out only when the first model could not be saved); for --check-config
///   it is a note, since systemd's StateDirectory= creates it when the service starts.
/// - the experiments of every reach with a configured `nominal_setpoint`, planned around it as
///   the start plans them: one without room inside the actuator's limits is a warning note (the
///   daemon starts, logs it and refuses that experiment; its others still run).
/// @throws StartupError naming the file and the fix.
StartupNotes CheckStartup(const DaemonPlan& plan, bool for_start);

}  // namespace canalid::daemon
