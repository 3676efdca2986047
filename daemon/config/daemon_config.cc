#include "daemon/config/daemon_config.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "core/experiment/experiment_design.h"
#include "core/online/online_arx.h"
#include "core/results/results_layout.h"
#include "core/signal/prbs.h"

namespace canalid::config {
using namespace canalid::core;  // NOLINT(google-build-using-namespace): the maths the schema uses
using namespace canalid::drivers;  // NOLINT(google-build-using-namespace): scaling, commands
namespace {

constexpr std::array kLogLevels{LogLevel::kError, LogLevel::kWarn, LogLevel::kInfo,
                                LogLevel::kDebug};
constexpr std::array kTransports{PlcTransport::kTcp, PlcTransport::kRtu};
constexpr std::array kRoles{ChannelRole::kLevel, ChannelRole::kFlow,      ChannelRole::kGate,
                            ChannelRole::kPump,  ChannelRole::kHeartbeat, ChannelRole::kOther};
constexpr std::array kTables{RegisterTable::kInput, RegisterTable::kHolding};
constexpr std::array kTypes{RegisterType::kU16, RegisterType::kI16, RegisterType::kU32,
                            RegisterType::kI32, RegisterType::kF32};
constexpr std::array kWordOrders{WordOrder::kHighWordFirst, WordOrder::kLowWordFirst};
constexpr std::array kBatchModels{BatchModel::kId,        BatchModel::kIdz,   BatchModel::kFoptd,
                                  BatchModel::kFracFoptd, BatchModel::kSoptd, BatchModel::kArx,
                                  BatchModel::kFracSs};
constexpr std::array kClosedLoopModes{ClosedLoopMode::kAuto, ClosedLoopMode::kOn,
                                      ClosedLoopMode::kOff};
constexpr std::array kRlsMethods{RlsMethod::kUdDirectional, RlsMethod::kUdExponential,
                                 RlsMethod::kExponential,   RlsMethod::kDirectional,
                                 RlsMethod::kConstantTrace, RlsMethod::kStabilised,
                                 RlsMethod::kKalman,        RlsMethod::kNlms};
constexpr std::array kModes{ExperimentMode::kDesign, ExperimentMode::kExplicit,
                            ExperimentMode::kStep};
constexpr std::array kStarts{ExperimentStart::kManual, ExperimentStart::kOnStart};
constexpr std::array kCommandKinds{CommandKind::kStartExperiment, CommandKind::kAbortExperiment,
                                   CommandKind::kResetEstimator, CommandKind::kPublishConfig};

// Largest online delay bank (estimators = max delay in samples + 1): bounds memory and CPU.
constexpr double kMaxDelaySamples = 2000.0;

std::string Num(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string Quoted(const std::string& s) { return "\"" + s + "\""; }

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (char c : name) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

class Collector {
 public:
  void Add(std::string path, std::string message) {
    problems_.push_back({std::move(path), std::move(message)});
  }
  // lo <= value <= hi (bounds inclusive unless open_lo/open_hi), finite unless hi is inf.
  void Range(const std::string& path, double value, double lo, double hi, bool open_lo = false,
             bool open_hi = false) {
    const bool ok = !std::isnan(value) && (open_lo ? value > lo : value >= lo) &&
                    (open_hi ? value < hi : value <= hi);
    if (!ok) {
      Add(path, Num(value) + " is out of range (allowed: " + (open_lo ? "(" : "[") + Num(lo) +
                    ", " + Num(hi) + (open_hi ? ")" : "]") + ")");
    }
  }
  void IntRange(const std::string& path, std::int64_t value, std::int64_t lo, std::int64_t hi) {
    if (value < lo || value > hi) {
      Add(path, std::to_string(value) + " is out of range (allowed: " + std::to_string(lo) + ".." +
                    std::to_string(hi) + ")");
    }
  }
  void Name(const std::string& path, const std::string& name) {
    if (!ValidName(name)) {
      Add(path, Quoted(name) + " is not a valid name (allowed: 1 to 64 of A-Z a-z 0-9 _)");
    }
  }
  std::vector<ConfigProblem> Take() { return std::move(problems_); }

 private:
  std::vector<ConfigProblem> problems_;
};

std::string Index(const char* array, std::size_t i) {
  return std::string(array) + "[" + std::to_string(i) + "]";
}

void ValidateDaemon(const DaemonConfig& c, Collector& out) {
  const DaemonSection& d = c.daemon;
  if (d.state_directory.empty() || d.state_directory.front() != '/') {
    out.Add("daemon.state_directory",
            Quoted(d.state_directory) + " is not an absolute path (allowed: /...)");
  }
  out.Range("daemon.time_scale", d.time_scale, 0.0, 10000.0, true);
  if (d.heartbeat) {
    out.Range("daemon.heartbeat.period_s", d.heartbeat->period_s, 0.0, 3600.0, true);
    const ChannelConfig* ch = c.FindChannel(d.heartbeat->channel);
    if (ch == nullptr) {
      out.Add("daemon.heartbeat.channel",
              "unknown channel " + Quoted(d.heartbeat->channel) + " (allowed: a [[channel]] name)");
    } else if (ch->role != ChannelRole::kHeartbeat || !ch->writable) {
      out.Add("daemon.heartbeat.channel",
              "channel " + Quoted(ch->name) +
                  " is not a writable heartbeat channel (allowed: role = \"heartbeat\", writable = "
                  "true)");
    }
  }
  const std::string& url = c.lcm.url;
  const bool url_ok = url.empty() || url.starts_with("udpm://") || url.starts_with("memq://") ||
                      url.starts_with("file://") || url.starts_with("tcpq://");
  if (!url_ok) {
    out.Add("lcm.url",
            Quoted(url) + " is not an LCM URL (allowed: \"\", udpm://, memq://, file://, tcpq://)");
  }
  const std::string& prefix = c.lcm.channel_prefix;
  bool prefix_ok = prefix.size() <= 32;
  for (char ch : prefix) {
    prefix_ok = prefix_ok && ((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                              (ch >= '0' && ch <= '9') || ch == '_');
  }
  if (!prefix_ok) {
    out.Add("lcm.channel_prefix",
            Quoted(prefix) + " is not a channel prefix (allowed: 0 to 32 of A-Z a-z 0-9 _)");
  }
}

void ValidatePlcs(const DaemonConfig& c, Collector& out) {
  if (c.plcs.empty()) out.Add("plc", "no [[plc]] table (allowed: at least one)");
  std::set<std::string> names;
  for (std::size_t i = 0; i < c.plcs.size(); ++i) {
    const PlcConfig& p = c.plcs[i];
    const std::string at = Index("plc", i) + ".";
    out.Name(at + "name", p.name);
    if (!names.insert(p.name).second) out.Add(at + "name", "duplicate plc name " + Quoted(p.name));
    if (p.transport == PlcTransport::kTcp) {
      if (p.host.empty()) out.Add(at + "host", "is empty (allowed: a host name or address)");
      out.IntRange(at + "port", p.port, 1, 65535);
      out.IntRange(at + "unit_id", p.unit_id, 0, 255);
      out.Range(at + "connect_timeout_s", p.connect_timeout_s, 0.0, 60.0, true);
    } else {
      if (p.device.empty()) out.Add(at + "device", "is empty (allowed: a serial device path)");
      out.IntRange(at + "baud", p.baud, 300, 4000000);
      if (p.parity != 'N' && p.parity != 'E' && p.parity != 'O') {
        out.Add(at + "parity", Quoted(std::string(1, p.parity)) +
                                   " is not a parity (allowed: \"N\", \"E\", \"O\")");
      }
      out.IntRange(at + "data_bits", p.data_bits, 5, 8);
      out.IntRange(at + "stop_bits", p.stop_bits, 1, 2);
      out.IntRange(at + "unit_id", p.unit_id, 1, 247);
    }
    out.Range(at + "response_timeout_s", p.response_timeout_s, 0.0, 60.0, true);
    if (std::isfinite(p.response_timeout_s)) {
      out.Range(at + "poll_period_s", p.poll_period_s, p.response_timeout_s, 3600.0, true);
    }
    out.Range(at + "backoff_initial_s", p.backoff_initial_s, 0.0, 3600.0, true);
    out.Range(at + "backoff_max_s", p.backoff_max_s,
              std::isfinite(p.backoff_initial_s) ? p.backoff_initial_s : 0.0, 3600.0);
    out.IntRange(at + "max_gap_registers", p.max_gap_registers, 0, 125);
    out.IntRange(at + "timeouts_before_reconnect", p.timeouts_before_reconnect, 1, 1000);
    bool has_channel = false;
    for (const ChannelConfig& ch : c.channels) has_channel = has_channel || ch.plc == p.name;
    if (!has_channel) {
      out.Add(at + "name", "plc " + Quoted(p.name) + " has no channel (allowed: at least one)");
    }
  }
}

void ValidateChannels(const DaemonConfig& c, Collector& out) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < c.channels.size(); ++i) {
    const ChannelConfig& ch = c.channels[i];
    const std::string at = Index("channel", i) + ".";
    out.Name(at + "name", ch.name);
    if (!names.insert(ch.name).second) {
      out.Add(at + "name", "duplicate channel name " + Quoted(ch.name));
    }
    if (c.FindPlc(ch.plc) == nullptr) {
      out.Add(at + "plc", "unknown plc " + Quoted(ch.plc) + " (allowed: a [[plc]] name)");
    }
    out.IntRange(at + "address", ch.address, 0, 65536 - RegisterCount(ch.type));
    if (!(std::isfinite(ch.scale) && ch.scale != 0.0)) {
      out.Add(at + "scale", Num(ch.scale) + " is out of range (allowed: finite and nonzero)");
    }
    if (!std::isfinite(ch.offset)) {
      out.Add(at + "offset", Num(ch.offset) + " is out of range (allowed: finite)");
    }
    if (std::isnan(ch.valid_min)) {
      out.Add(at + "valid_min", "nan is out of range (allowed: a number, -inf = no bound)");
    }
    if (std::isnan(ch.valid_max) || ch.valid_max < ch.valid_min) {
      out.Add(at + "valid_max", Num(ch.valid_max) + " is out of range (allowed: >= valid_min " +
                                    Num(ch.valid_min) + ")");
    }
    if (!ch.writable) continue;
    if (ch.table != RegisterTable::kHolding) {
      out.Add(at + "writable",
              "an input register cannot be written (allowed: register = "
              "\"holding\")");
    }
    const ChannelScaling scaling{ch.type,   ch.word_order, ch.scale,
                                 ch.offset, ch.valid_min,  ch.valid_max};
    const bool scaling_ok = std::isfinite(ch.scale) && ch.scale != 0.0 &&
                            std::isfinite(ch.offset) && ch.valid_min <= ch.valid_max;
    auto check_setpoint = [&](const char* key, double value) {
      if (!std::isfinite(value) || value < ch.valid_min || value > ch.valid_max) {
        out.Add(at + key, Num(value) + " is out of range (allowed: [" + Num(ch.valid_min) + ", " +
                              Num(ch.valid_max) + "], finite)");
        return;
      }
      std::array<uint16_t, 2> registers{};
      if (scaling_ok && EncodeChannel(scaling, value,
                                      std::span(registers.data(), static_cast<std::size_t>(
                                                                      RegisterCount(ch.type)))) !=
                            ScalingError::kNone) {
        out.Add(at + key, Num(value) + " does not fit register type " + Quoted(EnumName(ch.type)) +
                              " with this scale and offset");
      }
    };
    check_setpoint("setpoint_min", ch.setpoint_min);
    check_setpoint("setpoint_max", ch.setpoint_max);
    if (std::isfinite(ch.setpoint_min) && ch.setpoint_max < ch.setpoint_min) {
      out.Add(at + "setpoint_max", Num(ch.setpoint_max) +
                                       " is out of range (allowed: >= "
                                       "setpoint_min " +
                                       Num(ch.setpoint_min) + ")");
    }
    // Two writers of one register would defeat each other's clamp and rate limit.
    for (std::size_t j = 0; j < i; ++j) {
      const ChannelConfig& other = c.channels[j];
      if (other.writable && other.plc == ch.plc && other.table == ch.table &&
          ch.address < other.address + RegisterCount(other.type) &&
          other.address < ch.address + RegisterCount(ch.type)) {
        out.Add(at + "address", std::to_string(ch.address) + " overlaps writable channel " +
                                    Quoted(other.name) + " (allowed: one writer per register)");
      }
    }
    if (!(ch.max_rate_per_s > 0.0)) {
      out.Add(at + "max_rate_per_s",
              Num(ch.max_rate_per_s) + " is out of range (allowed: > 0, inf = no limit)");
    }
  }
}

// A reach's channel reference: exists, has one of `roles`, is writable if asked.
const ChannelConfig* CheckReachChannel(const DaemonConfig& c, const std::string& path,
                                       const std::string& name,
                                       std::initializer_list<ChannelRole> roles, bool writable,
                                       Collector& out) {
  const ChannelConfig* ch = c.FindChannel(name);
  if (ch == nullptr) {
    out.Add(path, "unknown channel " + Quoted(name) + " (allowed: a [[channel]] name)");
    return nullptr;
  }
  bool role_ok = false;
  std::string allowed;
  for (ChannelRole r : roles) {
    role_ok = role_ok || ch->role == r;
    allowed += (allowed.empty() ? "" : " or ") + Quoted(EnumName(r));
  }
  if (!role_ok) {
    out.Add(path, "channel " + Quoted(name) + " has role " + Quoted(EnumName(ch->role)) +
                      " (allowed: " + allowed + ")");
  }
  if (writable && !ch->writable) {
    out.Add(path, "channel " + Quoted(name) + " is not writable (allowed: writable = true)");
  }
  return ch;
}

// Each model of a list at most once.
template <class E>
void NoDuplicates(const std::string& path, const std::vector<E>& models, Collector& out) {
  std::set<E> seen;
  for (std::size_t m = 0; m < models.size(); ++m) {
    if (!seen.insert(models[m]).second) {
      out.Add(path + "[" + std::to_string(m) + "]",
              "duplicate model " + Quoted(EnumName(models[m])) + " (allowed: each of " +
                  AllowedNames<E>() + " once)");
    }
  }
}

// The process models' settings and channels of a reach (arx, frac-foptd, lpv).
void ValidateReachModels(const DaemonConfig& c, const ReachConfig& r, const ChannelConfig* level,
                         const std::string& at, Collector& out) {
  // A channel of the reach beside the four: exists, on the level's plc.
  auto extra_channel = [&](const char* key, const std::string& name,
                           std::initializer_list<ChannelRole> roles) {
    const ChannelConfig* ch = CheckReachChannel(c, at + key, name, roles, false, out);
    if (ch != nullptr && level != nullptr && ch->plc != level->plc) {
      out.Add(at + key, "channel " + Quoted(name) + " is on plc " + Quoted(ch->plc) +
                            " (allowed: the level's plc " + Quoted(level->plc) + ")");
    }
  };
  if (!r.actuator_position.empty()) {
    extra_channel("actuator_position", r.actuator_position,
                  {ChannelRole::kGate, ChannelRole::kPump});
  }
  const bool lpv = std::find(r.online_models.begin(), r.online_models.end(),
                             OnlineModel::kLpvArx) != r.online_models.end();
  const bool batch_idz = std::find(r.batch_models.begin(), r.batch_models.end(),
                                   BatchModel::kIdz) != r.batch_models.end();
  const bool idz = batch_idz || std::find(r.online_models.begin(), r.online_models.end(),
                                          OnlineModel::kIdz) != r.online_models.end();
  if (r.id_wave_front && std::find(r.online_models.begin(), r.online_models.end(),
                                   OnlineModel::kIntegratorDelay) == r.online_models.end()) {
    out.Add(at + "id_wave_front", "has no effect: online_models has no \"id\"");
  }
  if (r.idz_p22_s_per_m2) {
    if (!idz) {
      out.Add(at + "idz_p22_s_per_m2",
              "has no effect: neither batch_models nor online_models has \"idz\"");
    }
    out.Range(at + "idz_p22_s_per_m2", *r.idz_p22_s_per_m2, 0.0, 10.0);
  }
  if (r.idz_p22_std_s_per_m2) {
    if (!r.idz_p22_s_per_m2) {
      out.Add(at + "idz_p22_std_s_per_m2", "has no effect without idz_p22_s_per_m2");
    } else if (!batch_idz) {  // the online kind holds p22 and has no use for its spread
      out.Add(at + "idz_p22_std_s_per_m2", "has no effect: batch_models has no \"idz\"");
    }
    out.Range(at + "idz_p22_std_s_per_m2", *r.idz_p22_std_s_per_m2, 0.0, 10.0);
  }
  if (!r.lpv_scheduling.empty()) {
    extra_channel("lpv_scheduling", r.lpv_scheduling,
                  {ChannelRole::kLevel, ChannelRole::kFlow, ChannelRole::kGate, ChannelRole::kPump,
                   ChannelRole::kOther});
  } else if (lpv) {
    out.Add(at + "lpv_scheduling", "missing (required with online model \"lpv\")");
  }
  auto orders = [&](const char* na_key, int na, const char* nb_key, int nb) {
    out.Range(at + na_key, na, 0, core::kMaxOnlineArxParams - 1);
    out.Range(at + nb_key, nb, 1, core::kMaxOnlineArxParams);
    if (na >= 0 && nb >= 1 && na + nb > core::kMaxOnlineArxParams) {
      out.Add(at + nb_key, Num(nb) + " is out of range (allowed: " + na_key + " + " + nb_key +
                               " <= " + Num(core::kMaxOnlineArxParams) + ")");
    }
  };
  orders("arx_na", r.arx_na, "arx_nb", r.arx_nb);
  orders("lpv_na", r.lpv_na, "lpv_nb", r.lpv_nb);
  if (r.fractional_alphas.empty() || r.fractional_alphas.size() > 32) {
    out.Add(at + "fractional_alphas",
            Num(static_cast<double>(r.fractional_alphas.size())) + " values (allowed: 1 to 32)");
  }
  for (std::size_t k = 0; k < r.fractional_alphas.size(); ++k) {
    out.Range(at + "fractional_alphas[" + std::to_string(k) + "]", r.fractional_alphas[k], 0.0, 2.0,
              true, true);
  }
  double hi = 1e6;
  if (c.FindReachPlc(r) != nullptr) {
    const double ts = ReachSampleTimeS(c, r);
    if (ts > 0.0 && std::isfinite(ts)) hi = kMaxDelaySamples * ts;
  }
  // Checked for the kinds the reach runs: their defaults follow expected_delay_s, which may be
  // longer than a bank of 2000 samples.
  const auto runs = [&](OnlineModel m) {
    return std::find(r.online_models.begin(), r.online_models.end(), m) != r.online_models.end();
  };
  if (runs(OnlineModel::kFractionalFoptd)) {
    out.Range(at + "fractional_delay_s", r.fractional_delay_s, 0.0, hi);
  }
  if (lpv) out.Range(at + "lpv_delay_s", r.lpv_delay_s, 0.0, hi);
  if (runs(OnlineModel::kFracSs)) out.Range(at + "frac_ss_delay_s", r.frac_ss_delay_s, 0.0, hi);
  // The orders `canalid identify --model frac-ss --q` takes.
  if (r.frac_ss_q != 1 && r.frac_ss_q != 2 && r.frac_ss_q != 4) {
    out.Add(at + "frac_ss_q", Num(r.frac_ss_q) + " is out of range (allowed: 1, 2 or 4)");
  }
}

// The reaches with an experiment that another experiment runs `with` (partners of joint
// experiments).
std::set<std::string> PartnerReaches(const DaemonConfig& c) {
  std::set<std::string> reaches;
  for (const ExperimentConfig& e : c.experiments) {
    for (const std::string& name : e.with) {
      if (const ExperimentConfig* partner = c.FindExperiment(name)) reaches.insert(partner->reach);
    }
  }
  return reaches;
}

void ValidateReaches(const DaemonConfig& c, Collector& out) {
  const std::set<std::string> partners = PartnerReaches(c);
  std::set<std::string> names;
  for (std::size_t i = 0; i < c.reaches.size(); ++i) {
    const ReachConfig& r = c.reaches[i];
    const std::string at = Index("reach", i) + ".";
    out.Name(at + "name", r.name);
    if (!names.insert(r.name).second)
      out.Add(at + "name", "duplicate reach name " + Quoted(r.name));
    const ChannelConfig* level =
        CheckReachChannel(c, at + "level", r.level, {ChannelRole::kLevel}, false, out);
    const ChannelConfig* others[] = {
        CheckReachChannel(c, at + "inflow", r.inflow, {ChannelRole::kFlow}, false, out),
        CheckReachChannel(c, at + "outflow", r.outflow, {ChannelRole::kFlow}, false, out),
        CheckReachChannel(c, at + "actuator", r.actuator, {ChannelRole::kGate, ChannelRole::kPump},
                          true, out)};
    const char* keys[] = {"inflow", "outflow", "actuator"};
    // One poller delivers all of a reach's values in the same sample.
    for (int k = 0; k < 3; ++k) {
      if (level != nullptr && others[k] != nullptr && others[k]->plc != level->plc) {
        out.Add(at + keys[k], "channel " + Quoted(others[k]->name) + " is on plc " +
                                  Quoted(others[k]->plc) + " (allowed: the level's plc " +
                                  Quoted(level->plc) + ")");
      }
    }
    const ChannelConfig* actuator = others[2];
    if (r.nominal_setpoint && actuator != nullptr && actuator->writable) {
      out.Range(at + "nominal_setpoint", *r.nominal_setpoint, actuator->setpoint_min,
                actuator->setpoint_max);
    }
    if (r.actuator_gain_m3s_per_unit) {
      const double g = *r.actuator_gain_m3s_per_unit;
      if (!(std::isfinite(g) && g != 0.0)) {
        out.Add(at + "actuator_gain_m3s_per_unit",
                Num(g) + " is out of range (allowed: finite and nonzero)");
      }
    }
    out.Range(at + "nominal_inflow_m3s", r.nominal_inflow_m3s, 0.0, 1e5, true);
    out.Range(at + "expected_delay_s", r.expected_delay_s, 0.0, 1e6, true);
    if (!std::isfinite(r.level_min_m)) {
      out.Add(at + "level_min_m", Num(r.level_min_m) + " is out of range (allowed: finite)");
    }
    if (!(std::isfinite(r.level_max_m) && r.level_max_m > r.level_min_m)) {
      out.Add(at + "level_max_m", Num(r.level_max_m) +
                                      " is out of range (allowed: finite, > "
                                      "level_min_m " +
                                      Num(r.level_min_m) + ")");
    }
    NoDuplicates(at + "online_models", r.online_models, out);
    NoDuplicates(at + "batch_models", r.batch_models, out);
    if (r.batch_models.empty() && !r.online_models.empty()) {
      out.Add(at + "batch_models",
              "is empty (allowed: at least one of " + AllowedNames<BatchModel>() + ")");
    } else if (r.batch_models.empty() && partners.count(r.name) == 0) {
      // No model at all: the reach only moves its actuator, which it does in joint experiments.
      out.Add(at + "batch_models",
              "is empty and so is online_models: the reach does nothing (allowed: at least one "
              "of " +
                  AllowedNames<BatchModel>() +
                  ", or none when an experiment of the reach runs `with` another reach's)");
    }
    ValidateReachModels(c, r, level, at, out);
    out.Range(at + "model_publish_period_s", r.model_publish_period_s, 0.0, 1e6);
    out.Range(at + "forgetting", r.forgetting, 0.0, 1.0, true);
    if (r.initial_covariance) {
      out.Range(at + "initial_covariance", *r.initial_covariance, 0.0, 1e20, true);
    }
    out.Range(at + "min_delay_s", r.min_delay_s, 0.0, 1e6);
    if (std::isfinite(r.min_delay_s) && r.min_delay_s >= 0.0) {
      double hi = 1e6;
      if (c.FindReachPlc(r) != nullptr) {
        // A bad poll period or time scale is reported on its own key, not again here.
        const double ts = ReachSampleTimeS(c, r);
        if (ts > 0.0 && std::isfinite(ts)) hi = kMaxDelaySamples * ts;
      }
      if (r.max_delay_s < r.min_delay_s || !(r.max_delay_s <= hi)) {
        out.Add(at + "max_delay_s", Num(r.max_delay_s) +
                                        " is out of range (allowed: [min_delay_s " +
                                        Num(r.min_delay_s) + ", " + Num(hi) + "], " +
                                        Num(kMaxDelaySamples) + " samples)");
      }
    }
  }
}

// A duration of n >= 1 whole samples of Ts (unchecked when Ts is unknown: its keys report it).
void WholeSamples(const std::string& path, double seconds, double ts, Collector& out) {
  if (!(ts > 0.0)) return;
  const double samples = seconds / ts;
  if (!(samples >= 1.0 && samples <= 1e6 &&
        std::abs(samples - std::round(samples)) <= 1e-9 * samples)) {
    out.Add(path, Num(seconds) + " is not a whole number of samples (allowed: n * sample time " +
                      Num(ts) + " s, n >= 1)");
  }
}

// Returns each experiment's LFSR order (0: a step, or a design that cannot be made).
std::vector<int> ValidateExperiments(const DaemonConfig& c, Collector& out) {
  std::vector<int> orders;
  std::set<std::string> names;
  for (std::size_t i = 0; i < c.experiments.size(); ++i) {
    const ExperimentConfig& e = c.experiments[i];
    const std::string at = Index("experiment", i) + ".";
    out.Name(at + "name", e.name);
    if (!names.insert(e.name).second) {
      out.Add(at + "name", "duplicate experiment name " + Quoted(e.name));
    }
    const ReachConfig* reach = c.FindReach(e.reach);
    if (reach == nullptr) {
      out.Add(at + "reach", "unknown reach " + Quoted(e.reach) + " (allowed: a [[reach]] name)");
    }
    double ts = 0.0;
    if (reach != nullptr) {
      try {
        ts = ReachSampleTimeS(c, *reach);
      } catch (const std::invalid_argument&) {
        ts = 0.0;  // the reach's own problems are reported above
      }
    }
    int order = e.order;
    if (e.mode == ExperimentMode::kDesign) {
      out.Range(at + "amplitude_percent", e.amplitude_percent, 5.0, 10.0);
      out.Range(at + "duration_factor", e.duration_factor, 5.0, 20.0);
      // Only a design whose inputs are all in range can fail for its own reasons.
      const bool inputs_ok =
          reach != nullptr && ts > 0.0 && e.amplitude_percent >= 5.0 &&
          e.amplitude_percent <= 10.0 && e.duration_factor >= 5.0 && e.duration_factor <= 20.0 &&
          reach->nominal_inflow_m3s > 0.0 && std::isfinite(reach->nominal_inflow_m3s) &&
          reach->expected_delay_s > 0.0 && std::isfinite(reach->expected_delay_s);
      if (inputs_ok) {
        ExperimentDesignRequest request;
        request.nominal_flow_m3s = reach->nominal_inflow_m3s;
        request.expected_delay_s = reach->expected_delay_s;
        request.sample_time_s = ts;
        request.amplitude_percent = e.amplitude_percent;
        request.duration_factor = e.duration_factor;
        try {
          order = DesignPrbsExperiment(request).order;
        } catch (const std::invalid_argument& error) {
          out.Add(at + "mode",
                  std::string("no design for reach ") + Quoted(e.reach) + ": " + error.what());
          order = 0;
        }
      }
    } else if (e.mode == ExperimentMode::kStep) {
      if (!(std::isfinite(e.amplitude) && e.amplitude > 0.0)) {
        out.Add(at + "amplitude", Num(e.amplitude) + " is out of range (allowed: > 0, finite)");
      }
      WholeSamples(at + "hold_s", e.hold_s, ts, out);
    } else {
      if (!(std::isfinite(e.amplitude) && e.amplitude > 0.0)) {
        out.Add(at + "amplitude", Num(e.amplitude) + " is out of range (allowed: > 0, finite)");
      }
      out.IntRange(at + "order", e.order, kMinLfsrOrder, kMaxLfsrOrder);
      out.IntRange(at + "periods", e.periods, 1, 1000);
      WholeSamples(at + "clock_period_s", e.clock_period_s, ts, out);
    }
    if (e.seed < 1 || e.seed > 0x7fffffff) {
      out.IntRange(at + "seed", e.seed, 1, 0x7fffffff);
    } else if (order >= kMinLfsrOrder && order <= kMaxLfsrOrder &&
               (e.seed & ((std::int64_t{1} << order) - 1)) == 0) {
      out.Add(at + "seed", std::to_string(e.seed) + " has no nonzero bit among the low " +
                               std::to_string(order) + " (the LFSR order) (allowed: seed mod 2^" +
                               std::to_string(order) + " != 0)");
    }
    if (e.start == ExperimentStart::kOnStart) {
      for (std::size_t j = 0; j < i; ++j) {
        if (c.experiments[j].start == ExperimentStart::kOnStart &&
            c.experiments[j].reach == e.reach) {
          out.Add(at + "start", "experiment " + Quoted(c.experiments[j].name) + " already starts " +
                                    "reach " + Quoted(e.reach) +
                                    " on start (allowed: one per reach)");
        }
      }
    }
    out.Range(at + "settle_s", e.settle_s, 0.0, 1e7);
    out.IntRange(at + "max_invalid_samples", e.max_invalid_samples, 0, 1000);
    out.Range(at + "max_sample_gap_periods", e.max_sample_gap_periods, 1.1, 1000.0);
    orders.push_back(e.mode == ExperimentMode::kStep ? 0 : order);
  }
  return orders;
}

// `with`: the experiments of other reaches that run with this one (core/reach/joint_experiments.h).
void ValidateJointExperiments(const DaemonConfig& c, const std::vector<int>& orders,
                              Collector& out) {
  for (std::size_t i = 0; i < c.experiments.size(); ++i) {
    const ExperimentConfig& e = c.experiments[i];
    const ReachConfig* reach = c.FindReach(e.reach);
    std::set<std::string> reaches;
    for (std::size_t k = 0; k < e.with.size(); ++k) {
      const std::string at = Index("experiment", i) + ".with[" + std::to_string(k) + "]";
      const std::string& name = e.with[k];
      const ExperimentConfig* partner = c.FindExperiment(name);
      if (partner == nullptr) {
        out.Add(at, "unknown experiment " + Quoted(name) + " (allowed: an [[experiment]] name)");
        continue;
      }
      const std::string what = "experiment " + Quoted(name);
      if (partner->reach == e.reach) {
        out.Add(at, what + " is of the same reach " + Quoted(e.reach) +
                        " (allowed: an experiment of another reach)");
        continue;
      }
      if (!reaches.insert(partner->reach).second) {
        out.Add(at, what + " is a second one of reach " + Quoted(partner->reach) +
                        " (allowed: one experiment per reach)");
      }
      if (!partner->with.empty()) {
        out.Add(at, what +
                        " runs others with it (allowed: one without `with`; joint experiments "
                        "do not chain)");
      }
      if (partner->start == ExperimentStart::kOnStart) {
        out.Add(at, what + " starts on its own (allowed: start = \"manual\"; it starts with " +
                        Quoted(e.name) + ")");
      }
      // Two PRBS of one order whose registers start alike (the seeds' low `order` bits) are one
      // sequence: only their clocks would differ.
      const int order = orders[i];
      const auto partner_index = static_cast<std::size_t>(partner - c.experiments.data());
      if (order >= kMinLfsrOrder && order <= kMaxLfsrOrder && orders[partner_index] == order &&
          ((e.seed ^ partner->seed) & ((std::int64_t{1} << order) - 1)) == 0) {
        out.Add(at, what + " starts its LFSR of order " + std::to_string(order) +
                        " as this one does (seeds " + std::to_string(partner->seed) + " and " +
                        std::to_string(e.seed) + ") (allowed: another seed in the low " +
                        std::to_string(order) + " bits, so that the two PRBS are uncorrelated)");
      }
      const ReachConfig* other = c.FindReach(partner->reach);
      if (reach == nullptr || other == nullptr) continue;
      if (other->actuator == reach->actuator) {
        out.Add(at, what + " moves this experiment's actuator " + Quoted(reach->actuator) +
                        " (allowed: an experiment of a reach with another actuator)");
      }
      const PlcConfig* plc = c.FindReachPlc(*reach);
      const PlcConfig* other_plc = c.FindReachPlc(*other);
      if (plc != nullptr && other_plc != nullptr && plc != other_plc) {
        out.Add(at, what + " is of reach " + Quoted(other->name) + " on plc " +
                        Quoted(other_plc->name) + " (allowed: a reach on plc " + Quoted(plc->name) +
                        ", polled with this one)");
      }
    }
  }
}

void ValidateResults(const DaemonConfig& c, Collector& out) {
  const ResultsSection& r = c.results;
  out.IntRange("results.max_clients", r.max_clients, 1, 512);
  if (r.listen.empty()) return;
  if (!ParseListenAddress(r.listen)) {
    out.Add("results.listen", Quoted(r.listen) +
                                  " is not an address to listen on (allowed: \"host:port\" or "
                                  "\"[IPv6]:port\", port 0..65535)");
  }
  if (c.reaches.size() > static_cast<std::size_t>(core::kResultsMaxReaches)) {
    out.Add("results.listen", "the results map holds at most " +
                                  std::to_string(core::kResultsMaxReaches) + " reaches, not " +
                                  std::to_string(c.reaches.size()));
  }
}

void ValidateCommands(const DaemonConfig& c, Collector& out) {
  const CommandsSection& k = c.commands;
  if (k.enabled && (k.key_file.empty() || k.key_file.front() != '/')) {
    out.Add("commands.key_file",
            Quoted(k.key_file) + " is not an absolute path (allowed: /..., required when enabled)");
  }
  out.Range("commands.max_clock_skew_s", k.max_clock_skew_s, 0.0, 3600.0, true);
  std::set<CommandKind> kinds;
  for (std::size_t i = 0; i < k.accepted.size(); ++i) {
    if (!kinds.insert(k.accepted[i]).second) {
      out.Add("commands.accepted[" + std::to_string(i) + "]",
              "duplicate command " + Quoted(EnumName(k.accepted[i])));
    }
  }
}

template <class E, std::size_t N>
const char* NameIn(E value, const std::array<E, N>& values, const char* const (&names)[N]) {
  for (std::size_t i = 0; i < N; ++i) {
    if (values[i] == value) return names[i];
  }
  return "?";
}

}  // namespace

const PlcConfig* DaemonConfig::FindPlc(const std::string& name) const {
  for (const PlcConfig& p : plcs) {
    if (p.name == name) return &p;
  }
  return nullptr;
}
const ChannelConfig* DaemonConfig::FindChannel(const std::string& name) const {
  for (const ChannelConfig& c : channels) {
    if (c.name == name) return &c;
  }
  return nullptr;
}
const ReachConfig* DaemonConfig::FindReach(const std::string& name) const {
  for (const ReachConfig& r : reaches) {
    if (r.name == name) return &r;
  }
  return nullptr;
}
const ExperimentConfig* DaemonConfig::FindExperiment(const std::string& name) const {
  for (const ExperimentConfig& e : experiments) {
    if (e.name == name) return &e;
  }
  return nullptr;
}
const PlcConfig* DaemonConfig::FindReachPlc(const ReachConfig& reach) const {
  const ChannelConfig* level = FindChannel(reach.level);
  return level == nullptr ? nullptr : FindPlc(level->plc);
}

std::optional<ListenAddress> ParseListenAddress(std::string_view listen) {
  const std::size_t colon = listen.rfind(':');
  if (colon == std::string_view::npos || colon == 0) return std::nullopt;
  std::string_view host = listen.substr(0, colon);
  const std::string_view port = listen.substr(colon + 1);
  if (host.front() == '[') {
    if (host.size() < 3 || host.back() != ']') return std::nullopt;
    host = host.substr(1, host.size() - 2);
  } else if (host.find(':') != std::string_view::npos) {
    return std::nullopt;  // an IPv6 address needs its brackets
  }
  int value = 0;
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (error != std::errc() || end != port.data() + port.size() || value < 0 || value > 65535) {
    return std::nullopt;
  }
  return ListenAddress{std::string(host), value};
}

std::vector<ConfigProblem> Validate(const DaemonConfig& config) {
  Collector out;
  ValidateDaemon(config, out);
  ValidatePlcs(config, out);
  ValidateChannels(config, out);
  ValidateReaches(config, out);
  const std::vector<int> orders = ValidateExperiments(config, out);
  ValidateJointExperiments(config, orders, out);
  ValidateResults(config, out);
  ValidateCommands(config, out);
  return out.Take();
}

double ReachSampleTimeS(const DaemonConfig& config, const ReachConfig& reach) {
  const PlcConfig* plc = config.FindReachPlc(reach);
  if (plc == nullptr) {
    throw std::invalid_argument("reach " + Quoted(reach.name) + ": level channel " +
                                Quoted(reach.level) + " does not resolve to a plc");
  }
  return plc->poll_period_s * config.daemon.time_scale;
}

const char* EnumName(LogLevel v) {
  return NameIn(v, kLogLevels, {"error", "warn", "info", "debug"});
}
const char* EnumName(PlcTransport v) { return NameIn(v, kTransports, {"tcp", "rtu"}); }
const char* EnumName(ChannelRole v) {
  return NameIn(v, kRoles, {"level", "flow", "gate", "pump", "heartbeat", "other"});
}
const char* EnumName(RegisterTable v) { return NameIn(v, kTables, {"input", "holding"}); }
const char* EnumName(RegisterType v) {
  return NameIn(v, kTypes, {"u16", "i16", "u32", "i32", "f32"});
}
const char* EnumName(WordOrder v) { return NameIn(v, kWordOrders, {"high_first", "low_first"}); }
const char* EnumName(BatchModel v) {
  return NameIn(v, kBatchModels, {"id", "idz", "foptd", "frac-foptd", "soptd", "arx", "frac-ss"});
}
// A string_view of a literal: null-terminated.
const char* EnumName(OnlineModel v) { return core::OnlineModelKindName(v).data(); }
const char* EnumName(RlsMethod v) {
  return NameIn(v, kRlsMethods,
                {"ud_directional", "ud_exponential", "exponential", "directional", "constant_trace",
                 "stabilised", "kalman", "nlms"});
}
const char* EnumName(ClosedLoopMode v) {
  return NameIn(v, kClosedLoopModes, {"auto", "on", "off"});
}
const char* EnumName(ExperimentMode v) { return NameIn(v, kModes, {"design", "explicit", "step"}); }
const char* EnumName(ExperimentStart v) { return NameIn(v, kStarts, {"manual", "on_start"}); }
const char* EnumName(CommandKind v) {
  return NameIn(v, kCommandKinds,
                {"start_experiment", "abort_experiment", "reset_estimator", "publish_config"});
}

template <>
std::span<const LogLevel> AllValues<LogLevel>() {
  return kLogLevels;
}
template <>
std::span<const PlcTransport> AllValues<PlcTransport>() {
  return kTransports;
}
template <>
std::span<const ChannelRole> AllValues<ChannelRole>() {
  return kRoles;
}
template <>
std::span<const RegisterTable> AllValues<RegisterTable>() {
  return kTables;
}
template <>
std::span<const RegisterType> AllValues<RegisterType>() {
  return kTypes;
}
template <>
std::span<const WordOrder> AllValues<WordOrder>() {
  return kWordOrders;
}
template <>
std::span<const OnlineModel> AllValues<OnlineModel>() {
  return core::kOnlineModelKinds;
}
template <>
std::span<const BatchModel> AllValues<BatchModel>() {
  return kBatchModels;
}
template <>
std::span<const RlsMethod> AllValues<RlsMethod>() {
  return kRlsMethods;
}
template <>
std::span<const ClosedLoopMode> AllValues<ClosedLoopMode>() {
  return kClosedLoopModes;
}
template <>
std::span<const ExperimentMode> AllValues<ExperimentMode>() {
  return kModes;
}
template <>
std::span<const ExperimentStart> AllValues<ExperimentStart>() {
  return kStarts;
}
template <>
std::span<const CommandKind> AllValues<CommandKind>() {
  return kCommandKinds;
}

}  // namespace canalid::config
