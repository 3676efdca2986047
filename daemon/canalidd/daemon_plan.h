#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/reach/joint_experiments.h"
#include "core/reach/reach_controller.h"
#include "drivers/auth/command_auth.h"
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

/// One reach: the PLC it reads and what it runs (its channels are indices into that PLC's poll).
struct ReachWiring {
  int plc = 0;  ///< index into DaemonPlan::plcs; all of a reach's channels are on one PLC
  core::ReachControllerOptions runner;
  /// An online model is published on its first update and then every this many samples
  /// (model_publish_period_s / Ts, rounded; 1: on every update).
  std::int64_t model_publish_every = 1;
};

/// Everything the daemon runs, derived from the validated configuration.
struct DaemonPlan {
  std::string config_path;
  std::string config_text;  ///< effective configuration, published on LCM at start
  std::vector<PlcWiring> plcs;
  std::vector<ReachWiring> reaches;
  /// Experiments that run others with them (`with`), over indices into `reaches`.
  std::vector<core::JointExperiment> joints;
  std::string lcm_url;  ///< empty: LCM's default (LCM_DEFAULT_URL)
  std::string channel_prefix = "CANALID_";
  std::string state_directory;  ///< empty: no persistence
  double health_period_s = 10.0;
  bool commands_enabled = false;
  std::string command_key_file;
  double command_max_clock_skew_s = 5.0;
  std::vector<drivers::CommandKind> command_kinds;  ///< the kinds accepted (others are refused)
  /// The results register map ([results] listen): served when results_enabled.
  bool results_enabled = false;
  std::string results_host;
  int results_port = 0;
  int results_max_clients = 64;
};

}  // namespace canalid::daemon
