#pragma once
#include <cstdint>
#include <string>

#include "core/reach/reach_sample_processor.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// The health reports the daemon publishes on `<prefix>HEALTH`, one per component, with the
/// counter and gauge names of docs/lcm-channels.md.  Pure.

/// "plc.<name>": the poller's counters, read errors per kind and link gauges.
HealthReport PlcHealth(const std::string& plc_name, const drivers::PollerCounters& counters);
/// "lcm": handler and publish failures, connection losses and reconnects.
HealthReport BusHealth(int64_t handler_failures, int64_t publish_failures, int64_t losses,
                       int64_t reconnects);
/// "commands": the receiver's count per verdict and its callback failures.
HealthReport CommandHealth(const drivers::CommandReceiver& receiver);
/// "reach.<name>": samples, and the online bank's data counters when it runs.
HealthReport ReachHealth(const std::string& reach, const core::ReachSampleProcessor& pipeline);

}  // namespace canalid::daemon
