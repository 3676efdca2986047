#pragma once
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/integrator_delay/identify_integrator_delay.h"
#include "daemon/canalidd/daemon_runtime.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/state_store.h"

namespace canalid::daemon {

/// At start: the models of the state directory, each read back like any input (a file edited by
/// hand or written by a build without these checks must not come back as the reach's model:
/// PersistedModelProblem against the reach's bank), published on the bus and logged;
/// problems, leftover temp files and models of unknown reaches are logged or skipped.
void ResumePersistedModels(const StateStore& store,
                           const std::vector<std::unique_ptr<ReachRuntime>>& reaches,
                           LcmPublisher& publisher);

/// Models the daemon may persist at once: one per reach and batch kind (the save queue's size,
/// so that a new model never waits on the disk).
std::size_t BatchModelCount(const std::vector<std::unique_ptr<ReachRuntime>>& reaches);

/// The state file of a reach's identified model: the batch result's model JSON and, when the
/// reach runs an online bank, its snapshot (taken here, on the caller's thread: the bank is not
/// thread-safe), stamped `wall_time_s`.
PersistedModel MakePersistedModel(const ReachRuntime& reach,
                                  const core::IntegratorDelayIdentification& result,
                                  double wall_time_s);

}  // namespace canalid::daemon
