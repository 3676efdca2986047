#pragma once
#include <string>

#include "daemon/canalidd/daemon_runtime.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/state_store.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// The restore safety of a reach's experiments (the rules are in daemon.h): the experiment guard
/// written before the first excitation write and removed once the PLC confirms the nominal, and
/// the start-up decision on a guard a crash left.  `store` is nullptr without a state directory.
/// Blocking file I/O on the loop thread, once per experiment: the excitation write waits for it.

/// At start, before the pollers: core::DecideRestart on the guard left for `reach` (if any); a
/// restore it asks for is made pending (written once the PLC answers), the decision is logged and
/// published.  `actuator`: the reach's actuator channel in its PLC's poll.
void ResumeInterruptedExperiment(ReachRuntime& reach, const drivers::PollChannel& actuator,
                                 StateStore* store, LcmPublisher& publisher);

/// Writes the reach's experiment guard naming `actuator`; false (logged) when it is not durably
/// on disk.
bool PersistGuard(ReachRuntime& reach, const std::string& actuator, StateStore* store);

/// True when `result` (a write on the reach's actuator) is the PLC's confirmation of the reach's
/// pending restore: written, and equal to the target to 1e-9 relative.
bool ConfirmsRestore(const ReachRuntime& reach, const drivers::WriteResult& result);

/// The PLC confirmed the reach's pending restore: the guard is removed (unless a new experiment
/// is settling or exciting, or an operator must check a refused start-up) and the runner told.
void OnRestoreConfirmed(ReachRuntime& reach, StateStore* store);

}  // namespace canalid::daemon
