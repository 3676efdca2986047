#pragma once
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/command_auth.h"
#include "core/reach_pipeline.h"
#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// One PLC: its link, what to poll, and the optional heartbeat register the PLC's watchdog
/// watches.
struct PlcWiring {
  std::variant<drivers::ModbusTcpConfig, drivers::ModbusRtuConfig> link;
  drivers::PollerConfig poller;
  int heartbeat_channel = -1;  ///< index into poller.channels, -1: none
  double heartbeat_period_s = 1.0;
};

/// One reach: which channels of which PLC feed its pipeline and which one it excites.
struct ReachWiring {
  std::string name;
  int plc = 0;  ///< index into DaemonPlan::plcs; all of a reach's channels are on one PLC
  int q_in = -1, q_out = -1, level = -1, actuator = -1;  ///< channel indices in that PLC
  core::ReachPipelineOptions pipeline;  ///< sample_time_s = poll period x time scale; no experiment
  /// The actuator's nominal setpoint; none: its first valid reading.
  std::optional<double> nominal_setpoint;
  /// The reach's experiment for a nominal setpoint (empty: the reach is never excited).
  /// @throws std::invalid_argument when the nominal leaves no room for the PRBS inside the limits.
  std::function<core::ExperimentPlan(double nominal_setpoint)> experiment_for_nominal;
  bool start_experiment_on_start = false;
};

/// Everything the daemon runs, derived from the validated configuration.
struct DaemonPlan {
  std::string config_path;
  std::string config_text;  ///< effective configuration, published on LCM at start
  std::vector<PlcWiring> plcs;
  std::vector<ReachWiring> reaches;
  std::string lcm_url;  ///< empty: LCM's default (LCM_DEFAULT_URL)
  std::string channel_prefix = "CANALID_";
  std::string state_directory;  ///< empty: no persistence
  double health_period_s = 10.0;
  bool commands_enabled = false;
  std::string command_key_file;
  double command_max_clock_skew_s = 5.0;
  std::vector<core::CommandKind> command_kinds;  ///< the kinds accepted (others are refused)
};

}  // namespace canalid::daemon
