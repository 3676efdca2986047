#pragma once
#include <string>

#include "daemon/canalidd/daemon_plan.h"
#include "daemon/config/daemon_config.h"

namespace canalid::daemon {

/// Turns a validated configuration into what the daemon runs: Modbus links and poll lists per
/// PLC, the heartbeat channel, and per reach the channel indices, the online estimator options and
/// the experiment plan (designed from the rules of core/experiment/experiment_design.h, or
/// explicit), all in samples of sample_time_s = poll_period_s x time_scale.  `config_text` is
/// published on LCM.
/// @throws std::invalid_argument if the configuration does not resolve (Validate first).
DaemonPlan BuildDaemonPlan(const config::DaemonConfig& config, const std::string& config_path,
                           const std::string& config_text);

}  // namespace canalid::daemon
