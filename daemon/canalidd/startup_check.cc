#include "daemon/canalidd/startup_check.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "core/system/errno_text.h"
#include "daemon/canalidd/key_file.h"

namespace canalid::daemon {
namespace {

void CheckStateDirectory(const std::string& directory, bool for_start, StartupNotes& notes) {
  if (directory.empty()) return;  // no persistence
  const std::string what = "state directory " + directory;
  struct stat st {};
  if (::stat(directory.c_str(), &st) != 0) {
    const int error = errno;
    if (error == ENOENT) {
      const std::string message =
          what +
          " does not exist; systemd's StateDirectory= creates it when the service starts, "
          "otherwise create it (mkdir -m 700 " +
          directory + ", owned by the service user)";
      if (for_start) throw StartupError(message);
      notes.notes.push_back("note: " + message);
      return;
    }
    throw StartupError(what + ": cannot stat: " + core::ErrnoText(error));
  }
  if (!S_ISDIR(st.st_mode)) throw StartupError(what + " is not a directory");
  // The daemon writes a temp file and renames it: try exactly that much (create, then remove).
  std::string probe = directory + "/.canalidd-write-check.XXXXXX";
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) {
    throw StartupError(what + " is not writable by this user (" + core::ErrnoText(errno) +
                       "); models, experiment guards and command counters are saved there");
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

// Each experiment of a reach whose nominal setpoint is configured, planned around it as the
// daemon plans it at start (ReachExperiment::plan_for_nominal): one without room inside the
// actuator's limits is refused then, and the reach is only watched and estimated.
void CheckExperimentRoom(const DaemonPlan& plan, StartupNotes& notes) {
  for (const ReachWiring& reach : plan.reaches) {
    if (!reach.runner.nominal_setpoint) continue;
    const double nominal = *reach.runner.nominal_setpoint;
    for (const core::ReachExperiment& experiment : reach.runner.experiments) {
      try {
        experiment.plan_for_nominal(nominal).Validate();
      } catch (const std::invalid_argument& e) {
        notes.notes.push_back("warning: reach " + reach.runner.name + ": experiment '" +
                              experiment.name + "' cannot run around the configured nominal (" +
                              e.what() + "); the daemon will refuse it");
      }
    }
  }
}

}  // namespace

StartupNotes CheckStartup(const DaemonPlan& plan, bool for_start) {
  StartupNotes notes;
  if (plan.commands_enabled) {
    try {
      drivers::SecretBytes key = ReadKeyFile(plan.command_key_file);  // wiped on return
    } catch (const std::exception& e) {
      throw StartupError(e.what());
    }
  }
  CheckStateDirectory(plan.state_directory, for_start, notes);
  CheckExperimentRoom(plan, notes);
  return notes;
}

}  // namespace canalid::daemon
