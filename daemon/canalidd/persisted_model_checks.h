#pragma once
#include <string>

#include "core/online/online_integrator_delay.h"
#include "daemon/canalidd/state_store.h"

namespace canalid::daemon {

/// Why a persisted integrator-delay model cannot be resumed as the model of a reach whose online
/// bank has these options (empty when it can), checked like any input: kind "id" or "idz",
/// readable by drivers::IntegratorDelayModelFromJson or IdzModelFromJson (b finite, nk an integer
/// >= 0, ...), sample_time_s present and equal to the bank's Ts, delay_s (when present) finite and
/// equal to nk Ts and area_m2 (when present) equal to Ts / b (both to 1e-6), and inside
/// core::IntegratorDelayBoundsProblem (A > 0, nk within the bank and not at its edge).  Pure.
std::string PersistedIntegratorDelayProblem(const PersistedModel& model,
                                            const core::OnlineIntegratorDelayOptions& bank);

/// Why a persisted process model ("foptd", "soptd", "frac-foptd", "arx") cannot be resumed as the
/// model of a reach sampled every `sample_time_s` with delays up to `max_delay_s`: readable by its
/// drivers reader (drivers::FoptdFromJson, FractionalFoptdFromJson: finite, T > 0, 0 < alpha < 2
/// ...), sample_time_s present and equal to the reach's (to 1e-6), gain finite, delay in [0,
/// max_delay_s].  Pure.
std::string PersistedProcessModelProblem(const PersistedModel& model, double sample_time_s,
                                         double max_delay_s);

/// The check of the model's kind: one of the two above; any other kind is refused.
std::string PersistedModelProblem(const PersistedModel& model,
                                  const core::OnlineIntegratorDelayOptions& bank);

}  // namespace canalid::daemon
