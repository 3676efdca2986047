#pragma once
#include <string>

#include "daemon/canalidd/daemon_runtime.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/state_store.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// The file side of a reach's restore safety (the rules are core::ReachController's): the
/// experiment guard written before the first excitation write and removed once the PLC confirms
/// the nominal, and the start-up decision on a guard a crash left.  `store` is nullptr without a
/// state directory. Blocking file I/O on the loop thread, once per experiment: the excitation
/// write waits for it.

/// At start, before the pollers: core::DecideRestart on the guard left for `reach` (if any),
/// applied to its controller (a restore it asks for is written once the PLC answers), logged and
/// published.  `actuator`: the reach's actuator channel in its PLC's poll.
void ResumeInterruptedExperiment(ReachRuntime& reach, const drivers::PollChannel& actuator,
                                 StateStore* store, LcmPublisher& publisher);

/// Writes the reach's experiment guard naming `actuator` (and tells the controller); false
/// (logged) when it is not durably on disk.
bool PersistGuard(ReachRuntime& reach, const std::string& actuator, StateStore* store);

/// Removes the reach's experiment guard (the controller said it is done with); a failure is
/// logged, and the file, naming a nominal the PLC has confirmed, is rewritten by the next
/// experiment.
void RemoveGuard(const ReachRuntime& reach, StateStore* store);

}  // namespace canalid::daemon
