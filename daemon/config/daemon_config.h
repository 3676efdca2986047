#pragma once
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/integrator_delay/integrator_delay_model.h"
#include "core/online/online_model.h"
#include "core/online/rls_options.h"
#include "drivers/auth/command_auth.h"
#include "drivers/modbus/channel_scaling.h"

namespace canalid::config {

// Types of the layers below that the schema uses.
using core::ClosedLoopMode;
using core::RlsMethod;
using core::WordOrder;
using drivers::CommandKind;
using drivers::RegisterType;

// The whole configuration of canalidd as plain values (docs/configuration.md has every key).
// Durations of the link (timeouts, poll period, backoff, heartbeat) are wall-clock seconds;
// durations of the plant (delays, settling, PRBS clock) are plant seconds. One sample of a PLC
// lasts
//   sample_time_s = poll_period_s * time_scale   plant seconds.

enum class LogLevel { kError, kWarn, kInfo, kDebug };
enum class PlcTransport { kTcp, kRtu };
enum class ChannelRole { kLevel, kFlow, kGate, kPump, kHeartbeat, kOther };
/// Modbus table of a channel (function 4 input registers, function 3 holding registers).
enum class RegisterTable { kInput, kHolding };
/// The online model kinds are core's registry's (the names of core::OnlineModelKindName).
using OnlineModel = core::OnlineModelKind;
/// The models identified at the end of an experiment.
enum class BatchModel { kId, kIdz, kFoptd, kFracFoptd, kSoptd, kArx, kFracSs };
enum class ExperimentMode { kDesign, kExplicit, kStep };
enum class ExperimentStart { kManual, kOnStart };

/// The PLC's watchdog register, written with a changing value every period_s (wall seconds).
struct HeartbeatConfig {
  std::string channel;    ///< a writable channel with role heartbeat
  double period_s = 1.0;  ///< (0, 3600]
  bool operator==(const HeartbeatConfig&) const = default;
};

struct DaemonSection {
  std::string state_directory = "/var/lib/canalidd";  ///< absolute path
  LogLevel log_level = LogLevel::kInfo;
  double time_scale = 1.0;  ///< plant seconds per wall second, (0, 10000]
  std::optional<HeartbeatConfig> heartbeat;
  bool operator==(const DaemonSection&) const = default;
};

struct LcmSection {
  std::string url;                          ///< "" = LCM's default ($LCM_DEFAULT_URL)
  std::string channel_prefix = "CANALID_";  ///< [A-Za-z0-9_], at most 32 characters
  bool operator==(const LcmSection&) const = default;
};

/// One PLC reached over Modbus TCP or RTU, polled every poll_period_s.
struct PlcConfig {
  std::string name;
  PlcTransport transport = PlcTransport::kTcp;
  // TCP
  std::string host = "127.0.0.1";
  int port = 502;                  ///< 1..65535
  double connect_timeout_s = 1.0;  ///< (0, 60]
  // RTU
  std::string device;
  int baud = 19200;   ///< 300..4000000
  char parity = 'E';  ///< 'N', 'E' or 'O'
  int data_bits = 8;  ///< 5..8
  int stop_bits = 1;  ///< 1 or 2
  // Both
  int unit_id = 1;                    ///< TCP 0..255, RTU 1..247
  double response_timeout_s = 0.2;    ///< (0, 60]
  double poll_period_s = 1.0;         ///< (response_timeout_s, 3600]
  double backoff_initial_s = 0.5;     ///< (0, backoff_max_s]
  double backoff_max_s = 30.0;        ///< [backoff_initial_s, 3600]
  int max_gap_registers = 8;          ///< 0..125
  int timeouts_before_reconnect = 3;  ///< 1..1000
  bool operator==(const PlcConfig&) const = default;
};

/// One value read from a PLC: engineering = raw * scale + offset, valid in [valid_min, valid_max].
struct ChannelConfig {
  std::string name;
  std::string plc;
  ChannelRole role = ChannelRole::kOther;
  RegisterTable table = RegisterTable::kHolding;
  int address = 0;  ///< 0-based, the last register used <= 65535
  RegisterType type = RegisterType::kU16;
  WordOrder word_order = WordOrder::kHighWordFirst;
  double scale = 1.0;   ///< finite, nonzero
  double offset = 0.0;  ///< finite
  std::string unit;
  double valid_min = -std::numeric_limits<double>::infinity();
  double valid_max = std::numeric_limits<double>::infinity();
  bool writable = false;  ///< holding registers only
  // Used when writable (all three required then):
  double setpoint_min = 0.0;    ///< finite, inside [valid_min, valid_max], encodable
  double setpoint_max = 0.0;    ///< finite, >= setpoint_min, inside the valid range, encodable
  double max_rate_per_s = 0.0;  ///< per plant second, > 0, inf = no rate limit
  bool operator==(const ChannelConfig&) const = default;
};

/// A canal pool: the channels of its flows, level and the actuator of its inflow, and the
/// online estimators that run on it.
struct ReachConfig {
  std::string name;
  std::string inflow;    ///< channel with role flow
  std::string outflow;   ///< channel with role flow
  std::string level;     ///< channel with role level
  std::string actuator;  ///< writable channel with role gate or pump
  /// Nominal actuator setpoint (its unit); absent: the actuator's reading at start.
  std::optional<double> nominal_setpoint;
  /// Flow per unit of actuator around nominal (m3/s per unit); absent: flow proportional to the
  /// setting (gate opening at constant head, pump setting in m3/s).
  std::optional<double> actuator_gain_m3s_per_unit;
  double nominal_inflow_m3s = 0.0;  ///< > 0
  double expected_delay_s = 0.0;    ///< > 0, plant seconds
  double level_min_m = 0.0;         ///< safety band, finite, < level_max_m
  double level_max_m = 0.0;
  std::vector<OnlineModel> online_models{OnlineModel::kIntegratorDelay};  ///< no duplicates
  /// Identified at the end of each experiment, published with estimator "batch" and persisted;
  /// at least one, no duplicates.
  std::vector<BatchModel> batch_models{BatchModel::kId};
  /// idz: the prior of the outflow's direct gain p22 (s/m2, [0, 10]; `canalid theory`'s
  /// p22_low_frequency_s_per_m2 at the nominal inflow) and its standard deviation (default 20 %
  /// of it).  Batch: absent, p22 comes from the data when the outflow moves on its own, else is
  /// 0.  Online: held in the bank (absent: 0, the id bank with the wave front).
  std::optional<double> idz_p22_s_per_m2;
  std::optional<double> idz_p22_std_s_per_m2;
  /// The actuator's measured position (role gate or pump; empty: none): the process models'
  /// input when given, else the actuator's own reading (its setpoint).
  std::string actuator_position;
  int arx_na = 2;  ///< arx: output lags, 0..15
  int arx_nb = 2;  ///< arx: input lags, 1..16, arx_na + arx_nb <= 16
  /// frac-foptd: the alpha grid, 1..32 values in (0, 2).
  std::vector<double> fractional_alphas{0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4};
  double fractional_delay_s = 0.0;  ///< frac-foptd: known delay (default expected_delay_s)
  std::string lpv_scheduling;       ///< lpv: the scheduling channel, required with lpv
  int lpv_na = 1;                   ///< lpv: as arx_na
  int lpv_nb = 1;                   ///< lpv: as arx_nb
  double lpv_delay_s = 0.0;         ///< lpv: known delay (default expected_delay_s)
  int frac_ss_q = 2;                ///< frac-ss (online and batch): alpha = 1/q, 1, 2 or 4
  double frac_ss_delay_s = 0.0;     ///< online frac-ss: known delay (default expected_delay_s)
  /// Each online model is published at most once per this many plant s (rounded to whole
  /// samples; 0: on every update), [0, 1e6].
  double model_publish_period_s = 0.0;
  double min_delay_s = 0.0;  ///< smallest delay tried online, >= 0
  double max_delay_s = 0.0;  ///< largest, >= min_delay_s, at most 2000 samples
  double forgetting = 1.0;   ///< (0, 1]
  /// Every online estimator's P0 = initial_covariance I, (0, 1e20]; absent:
  /// core::kDefaultInitialCovariance.
  std::optional<double> initial_covariance;
  RlsMethod rls_method = RlsMethod::kUdDirectional;
  /// Batch identification at the end of an experiment: "auto" decides from the data whether the
  /// outflow follows the level (three-step closed-loop method), "on"/"off" force it.
  ClosedLoopMode closed_loop = ClosedLoopMode::kAuto;
  /// Online id: the bank fits the wave front's direct gain p21 >= 0 beside the integrator (as the
  /// batch id fit and `canalid identify --online --model id` do). Absent: true.
  std::optional<bool> id_wave_front;
  bool operator==(const ReachConfig&) const = default;
};

/// An experiment on a reach's actuator: a PRBS designed from the rules
/// (core/experiment/experiment_design.h) or given explicitly, or a step and back.
struct ExperimentConfig {
  std::string name;
  std::string reach;
  ExperimentMode mode = ExperimentMode::kDesign;
  // design
  double amplitude_percent = 7.5;  ///< of the nominal inflow, 5..10
  double duration_factor = 5.0;    ///< duration in expected delays, 5..20
  // explicit
  double amplitude = 0.0;       ///< actuator units, > 0
  double clock_period_s = 0.0;  ///< plant s, a whole number of samples (>= 1)
  int order = 7;                ///< 2..31
  int periods = 1;              ///< 1..1000
  // step (amplitude as explicit)
  double hold_s = 0.0;  ///< plant s at nominal + amplitude, then as long at nominal; n x Ts
  // both
  std::int64_t seed = 1;  ///< 1..2^31-1, nonzero in its low `order` bits
  double settle_s = 0.0;  ///< plant s at nominal before the PRBS, >= 0
  ExperimentStart start = ExperimentStart::kManual;
  int max_invalid_samples = 3;  ///< 0..1000
  /// Largest time between two samples of a running experiment, in poll periods of the reach's
  /// PLC, [1.1, 1000]; a longer gap (a stall, an overrun, a reconnect) aborts it.
  double max_sample_gap_periods = 1.5;
  /// Experiments of other reaches that run with this one, by name (a joint experiment,
  /// core/reach/joint_experiments.h: they start with it, end with it, done, when its excitation
  /// ends, and an abort of any stops all). A pool's two-structure experiment names its offtake's
  /// here.
  std::vector<std::string> with;
  bool operator==(const ExperimentConfig&) const = default;
};

struct CommandsSection {
  bool enabled = false;
  std::string key_file;           ///< required (absolute path) when enabled
  double max_clock_skew_s = 5.0;  ///< (0, 3600]
  std::vector<CommandKind> accepted{CommandKind::kStartExperiment, CommandKind::kAbortExperiment,
                                    CommandKind::kResetEstimator, CommandKind::kPublishConfig};
  bool operator==(const CommandsSection&) const = default;
};

/// The results register map (docs/results-register-map.md): off unless `listen` is given.
struct ResultsSection {
  /// "host:port" ("[v6]:port" for IPv6; port 0: any free port, logged); "" = no results map
  std::string listen;
  int max_clients = 64;  ///< [1, 512] connections at once
  bool operator==(const ResultsSection&) const = default;
};

/// `listen`'s host and port; nullopt when it is not "host:port" with a port in 0..65535.
struct ListenAddress {
  std::string host;
  int port = 0;
};
std::optional<ListenAddress> ParseListenAddress(std::string_view listen);

struct DaemonConfig {
  DaemonSection daemon;
  LcmSection lcm;
  ResultsSection results;
  std::vector<PlcConfig> plcs;
  std::vector<ChannelConfig> channels;
  std::vector<ReachConfig> reaches;
  std::vector<ExperimentConfig> experiments;
  CommandsSection commands;
  bool operator==(const DaemonConfig&) const = default;

  /// Lookups by name; nullptr when absent.
  const PlcConfig* FindPlc(const std::string& name) const;
  const ChannelConfig* FindChannel(const std::string& name) const;
  const ReachConfig* FindReach(const std::string& name) const;
  const ExperimentConfig* FindExperiment(const std::string& name) const;
  /// The PLC of `reach`: the PLC of its level channel (validation keeps all of a reach's channels
  /// on it); nullptr when the level channel or its plc is absent.
  const PlcConfig* FindReachPlc(const ReachConfig& reach) const;
};

/// One problem: the key path in TOML's own syntax with 0-based array indices
/// ("channel[2].plc", "daemon.heartbeat.period_s") and a message ending in "(allowed: ...)" when
/// there is a range.
struct ConfigProblem {
  std::string path;
  std::string message;
  bool operator==(const ConfigProblem&) const = default;
};

/// Every problem of `config` (none: valid): ranges, names (unique, [A-Za-z0-9_]{1,64}: they end LCM
/// channel names), references (channel -> plc, reach -> channels with the right roles on one plc,
/// experiment -> reach, heartbeat -> channel), encodability of setpoint limits, designs that cannot
/// be built. Pure.
std::vector<ConfigProblem> Validate(const DaemonConfig& config);

/// poll_period_s * time_scale of the reach's PLC (the PLC of its level channel).
/// @throws std::invalid_argument if the reach or its channels do not resolve.
double ReachSampleTimeS(const DaemonConfig& config, const ReachConfig& reach);

// Names used in the TOML file (and so in messages and docs).
const char* EnumName(LogLevel value);
const char* EnumName(PlcTransport value);
const char* EnumName(ChannelRole value);
const char* EnumName(RegisterTable value);
const char* EnumName(RegisterType value);
const char* EnumName(WordOrder value);
const char* EnumName(OnlineModel value);
const char* EnumName(BatchModel value);
const char* EnumName(RlsMethod value);
const char* EnumName(ClosedLoopMode value);
const char* EnumName(ExperimentMode value);
const char* EnumName(ExperimentStart value);
const char* EnumName(CommandKind value);

/// All values of an enum above, in declaration order.
template <class E>
std::span<const E> AllValues();
template <>
std::span<const LogLevel> AllValues<LogLevel>();
template <>
std::span<const PlcTransport> AllValues<PlcTransport>();
template <>
std::span<const ChannelRole> AllValues<ChannelRole>();
template <>
std::span<const RegisterTable> AllValues<RegisterTable>();
template <>
std::span<const RegisterType> AllValues<RegisterType>();
template <>
std::span<const WordOrder> AllValues<WordOrder>();
template <>
std::span<const OnlineModel> AllValues<OnlineModel>();
template <>
std::span<const BatchModel> AllValues<BatchModel>();
template <>
std::span<const RlsMethod> AllValues<RlsMethod>();
template <>
std::span<const ClosedLoopMode> AllValues<ClosedLoopMode>();
template <>
std::span<const ExperimentMode> AllValues<ExperimentMode>();
template <>
std::span<const ExperimentStart> AllValues<ExperimentStart>();
template <>
std::span<const CommandKind> AllValues<CommandKind>();

/// "a, b, c": the names of AllValues<E>().
template <class E>
std::string AllowedNames() {
  std::string out;
  for (E value : AllValues<E>()) {
    if (!out.empty()) out += ", ";
    out += EnumName(value);
  }
  return out;
}

/// The value whose name is `name`, if any.
template <class E>
std::optional<E> EnumFromName(std::string_view name) {
  for (E value : AllValues<E>()) {
    if (name == EnumName(value)) return value;
  }
  return std::nullopt;
}

}  // namespace canalid::config
