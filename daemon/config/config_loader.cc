#include "daemon/config/config_loader.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace canalid::daemon {
namespace {

using config::ChannelConfig;
using config::DaemonConfig;
using config::ExperimentConfig;
using config::PlcConfig;
using config::ReachConfig;

std::string Quoted(std::string_view s) { return "\"" + std::string(s) + "\""; }

// Walks the document, filling the config and collecting problems with their positions. Every key
// read (and every table) records its position under its path, so that problems found later by
// core::Validate can be placed too.
class Reader {
 public:
  explicit Reader(core::TomlReader& toml) : toml_(toml) {}

  void Problem(const toml::source_region& where, std::string path, std::string message) {
    reported_.insert(path);
    toml_.Problem(where, std::move(path), std::move(message));
  }

  void Mark(const std::string& path, const toml::source_region& where) { toml_.Mark(path, where); }

  // Unknown keys are errors; `conditional` maps keys allowed only elsewhere to the reason.
  void Keys(const toml::table& table, const std::string& path,
            std::initializer_list<std::string_view> allowed,
            const std::map<std::string, std::string>& conditional = {}) {
    for (const auto& [k, where] : core::TomlReader::UnknownKeys(table, allowed)) {
      const auto it = conditional.find(k);
      if (it != conditional.end()) {
        Problem(where, Join(path, k), "only allowed when " + it->second);
      } else {
        Problem(where, Join(path, k), "unknown key (allowed: " + core::JoinNames(allowed) + ")");
      }
    }
  }

  static std::string Join(const std::string& path, std::string_view key) {
    return core::TomlKeyPath(path, key);
  }

  const toml::node* Get(const toml::table& table, const std::string& path, std::string_view key,
                        bool required) {
    const toml::node* node = table.get(key);
    if (node != nullptr) {
      Mark(Join(path, key), node->source());
    } else if (required) {
      Problem(table.source(), Join(path, key), "missing (required)");
    }
    return node;
  }

  // A TOML float or integer as a double; false (reported at `at`) for anything else.
  bool NumberOf(const toml::node& node, const std::string& at, double& out) {
    if (const auto* f = node.as_floating_point()) {
      out = f->get();
    } else if (const auto* i = node.as_integer()) {
      out = static_cast<double>(i->get());
    } else {
      Problem(node.source(), at, std::string("expected a number, got ") + core::TomlTypeName(node));
      return false;
    }
    return true;
  }

  void Double(const toml::table& t, const std::string& path, std::string_view key, double& out,
              bool required = false) {
    const toml::node* node = Get(t, path, key, required);
    if (node != nullptr) NumberOf(*node, Join(path, key), out);
  }

  void OptionalDouble(const toml::table& t, const std::string& path, std::string_view key,
                      std::optional<double>& out) {
    if (t.get(key) == nullptr) return;
    double value = 0.0;
    Double(t, path, key, value);
    out = value;
  }

  template <class Int>
  void Integer(const toml::table& t, const std::string& path, std::string_view key, Int& out,
               bool required = false) {
    const toml::node* node = Get(t, path, key, required);
    if (node == nullptr) return;
    const auto* i = node->as_integer();
    if (i == nullptr) {
      Problem(node->source(), Join(path, key),
              std::string("expected an integer, got ") + core::TomlTypeName(*node));
      return;
    }
    const std::int64_t v = i->get();
    if (v < std::numeric_limits<Int>::min() || v > std::numeric_limits<Int>::max()) {
      Problem(node->source(), Join(path, key),
              std::to_string(v) + " is out of range (allowed: a " +
                  std::to_string(8 * sizeof(Int)) + "-bit integer)");
      return;
    }
    out = static_cast<Int>(v);
  }

  void OptionalBool(const toml::table& t, const std::string& path, std::string_view key,
                    std::optional<bool>& out) {
    if (t.get(key) == nullptr) return;
    bool value = false;
    Bool(t, path, key, value);
    out = value;
  }

  void Bool(const toml::table& t, const std::string& path, std::string_view key, bool& out) {
    const toml::node* node = Get(t, path, key, false);
    if (node == nullptr) return;
    if (const auto* b = node->as_boolean()) {
      out = b->get();
    } else {
      Problem(node->source(), Join(path, key),
              std::string("expected a boolean, got ") + core::TomlTypeName(*node));
    }
  }

  bool String(const toml::table& t, const std::string& path, std::string_view key, std::string& out,
              bool required = false) {
    const toml::node* node = Get(t, path, key, required);
    if (node == nullptr) return false;
    if (const auto* s = node->as_string()) {
      out = s->get();
      return true;
    }
    Problem(node->source(), Join(path, key),
            std::string("expected a string, got ") + core::TomlTypeName(*node));
    return false;
  }

  template <class E>
  bool EnumOf(const toml::node& node, const std::string& path, E& out) {
    const auto* s = node.as_string();
    if (s == nullptr) {
      Problem(node.source(), path,
              std::string("expected a string, got ") + core::TomlTypeName(node) +
                  " (allowed: " + config::AllowedNames<E>() + ")");
      return false;
    }
    const std::optional<E> value = config::EnumFromName<E>(s->get());
    if (!value) {
      Problem(node.source(), path,
              Quoted(s->get()) + " is not allowed (allowed: " + config::AllowedNames<E>() + ")");
      return false;
    }
    out = *value;
    return true;
  }

  template <class E>
  void Enum(const toml::table& t, const std::string& path, std::string_view key, E& out,
            bool required = false) {
    const toml::node* node = Get(t, path, key, required);
    if (node != nullptr) EnumOf(*node, Join(path, key), out);
  }

  // An array at `key`: `element(node, "key[i]", value)` reads each element (false: reported).
  template <class T, class Element>
  void List(const toml::table& t, const std::string& path, std::string_view key,
            const std::string& allowed, std::vector<T>& out, Element element) {
    const toml::node* node = Get(t, path, key, false);
    if (node == nullptr) return;
    const auto* array = node->as_array();
    if (array == nullptr) {
      Problem(node->source(), Join(path, key),
              std::string("expected an array, got ") + core::TomlTypeName(*node) +
                  " (allowed: " + allowed + ")");
      return;
    }
    out.clear();
    for (std::size_t i = 0; i < array->size(); ++i) {
      const std::string at = Join(path, key) + "[" + std::to_string(i) + "]";
      const toml::node& item = *array->get(i);
      Mark(at, item.source());
      T value{};
      if (element(item, at, value)) out.push_back(value);
    }
  }

  template <class E>
  void EnumList(const toml::table& t, const std::string& path, std::string_view key,
                std::vector<E>& out) {
    List(t, path, key, "of " + config::AllowedNames<E>(), out,
         [&](const toml::node& item, const std::string& at, E& value) {
           return EnumOf(item, at, value);
         });
  }

  void StringList(const toml::table& t, const std::string& path, std::string_view key,
                  std::vector<std::string>& out) {
    List(t, path, key, "of strings", out,
         [&](const toml::node& item, const std::string& at, std::string& value) {
           if (const auto* text = item.as_string()) {
             value = text->get();
             return true;
           }
           Problem(item.source(), at,
                   std::string("expected a string, got ") + core::TomlTypeName(item));
           return false;
         });
  }

  void DoubleList(const toml::table& t, const std::string& path, std::string_view key,
                  std::vector<double>& out) {
    List(t, path, key, "of numbers", out,
         [&](const toml::node& item, const std::string& at, double& value) {
           return NumberOf(item, at, value);
         });
  }

  const toml::table* Table(const toml::table& parent, const std::string& path,
                           std::string_view key) {
    const toml::node* node = Get(parent, path, key, false);
    if (node == nullptr) return nullptr;
    if (const auto* table = node->as_table()) return table;
    Problem(node->source(), Join(path, key),
            std::string("expected a table, got ") + core::TomlTypeName(*node));
    return nullptr;
  }

  // [[key]]: an array of tables. Calls f(table, "key[i]") for each.
  template <class F>
  void Tables(const toml::table& root, std::string_view key, F&& f) {
    const toml::node* node = Get(root, "", key, false);
    if (node == nullptr) return;
    const auto* array = node->as_array();
    if (array == nullptr || !array->is_array_of_tables()) {
      Problem(node->source(), std::string(key),
              std::string("expected an array of tables [[") + std::string(key) + "]], got " +
                  core::TomlTypeName(*node));
      return;
    }
    for (std::size_t i = 0; i < array->size(); ++i) {
      const auto& table = *array->get(i)->as_table();
      const std::string at = std::string(key) + "[" + std::to_string(i) + "]";
      Mark(at, table.source());
      f(table, at);
    }
  }

  // Places a problem found by core::Validate at its key, or the nearest enclosing table.
  void Place(const config::ConfigProblem& problem) {
    // A key that could not be read keeps its default, which Validate may then flag again.
    if (reported_.count(problem.path) != 0) return;
    toml_.Problem(toml_.Locate(problem.path), problem.path, problem.message);
  }

 private:
  core::TomlReader& toml_;
  std::set<std::string> reported_;  // paths with a problem found while reading
};

void ReadDaemon(Reader& r, const toml::table& root, DaemonConfig& c) {
  const toml::table* t = r.Table(root, "", "daemon");
  if (t == nullptr) return;
  r.Keys(*t, "daemon", {"state_directory", "log_level", "time_scale", "heartbeat"});
  r.String(*t, "daemon", "state_directory", c.daemon.state_directory);
  r.Enum(*t, "daemon", "log_level", c.daemon.log_level);
  r.Double(*t, "daemon", "time_scale", c.daemon.time_scale);
  if (const toml::table* h = r.Table(*t, "daemon", "heartbeat")) {
    c.daemon.heartbeat.emplace();
    r.Keys(*h, "daemon.heartbeat", {"channel", "period_s"});
    r.String(*h, "daemon.heartbeat", "channel", c.daemon.heartbeat->channel, true);
    r.Double(*h, "daemon.heartbeat", "period_s", c.daemon.heartbeat->period_s);
  }
}

void ReadLcm(Reader& r, const toml::table& root, DaemonConfig& c) {
  const toml::table* t = r.Table(root, "", "lcm");
  if (t == nullptr) return;
  r.Keys(*t, "lcm", {"url", "channel_prefix"});
  r.String(*t, "lcm", "url", c.lcm.url);
  r.String(*t, "lcm", "channel_prefix", c.lcm.channel_prefix);
}

void ReadResults(Reader& r, const toml::table& root, DaemonConfig& c) {
  const toml::table* t = r.Table(root, "", "results");
  if (t == nullptr) return;
  r.Keys(*t, "results", {"listen", "max_clients"});
  r.String(*t, "results", "listen", c.results.listen);
  r.Integer(*t, "results", "max_clients", c.results.max_clients);
}

void ReadPlc(Reader& r, const toml::table& t, const std::string& at, PlcConfig& p) {
  r.String(t, at, "name", p.name, true);
  r.Enum(t, at, "transport", p.transport);
  const bool tcp = p.transport == config::PlcTransport::kTcp;
  const std::string tcp_only = "transport = \"tcp\"";
  const std::string rtu_only = "transport = \"rtu\"";
  const std::map<std::string, std::string> other =
      tcp ? std::map<std::string, std::string>{{"device", rtu_only},
                                               {"baud", rtu_only},
                                               {"parity", rtu_only},
                                               {"data_bits", rtu_only},
                                               {"stop_bits", rtu_only}}
          : std::map<std::string, std::string>{
                {"host", tcp_only}, {"port", tcp_only}, {"connect_timeout_s", tcp_only}};
  if (tcp) {
    r.Keys(t, at,
           {"name", "transport", "host", "port", "connect_timeout_s", "unit_id",
            "response_timeout_s", "poll_period_s", "backoff_initial_s", "backoff_max_s",
            "max_gap_registers", "timeouts_before_reconnect"},
           other);
    r.String(t, at, "host", p.host, true);
    r.Integer(t, at, "port", p.port);
    r.Double(t, at, "connect_timeout_s", p.connect_timeout_s);
  } else {
    r.Keys(t, at,
           {"name", "transport", "device", "baud", "parity", "data_bits", "stop_bits", "unit_id",
            "response_timeout_s", "poll_period_s", "backoff_initial_s", "backoff_max_s",
            "max_gap_registers", "timeouts_before_reconnect"},
           other);
    r.String(t, at, "device", p.device, true);
    r.Integer(t, at, "baud", p.baud);
    std::string parity(1, p.parity);
    if (r.String(t, at, "parity", parity)) {
      // A longer string is stored as '?' so that Validate reports it with the allowed values.
      p.parity = parity.size() == 1 ? parity[0] : '?';
    }
    r.Integer(t, at, "data_bits", p.data_bits);
    r.Integer(t, at, "stop_bits", p.stop_bits);
  }
  r.Integer(t, at, "unit_id", p.unit_id);
  r.Double(t, at, "response_timeout_s", p.response_timeout_s);
  r.Double(t, at, "poll_period_s", p.poll_period_s);
  r.Double(t, at, "backoff_initial_s", p.backoff_initial_s);
  r.Double(t, at, "backoff_max_s", p.backoff_max_s);
  r.Integer(t, at, "max_gap_registers", p.max_gap_registers);
  r.Integer(t, at, "timeouts_before_reconnect", p.timeouts_before_reconnect);
}

void ReadChannel(Reader& r, const toml::table& t, const std::string& at, ChannelConfig& ch) {
  r.Bool(t, at, "writable", ch.writable);
  const std::string needs_writable = "writable = true";
  r.Keys(
      t, at,
      ch.writable
          ? std::initializer_list<std::string_view>{"name", "plc", "role", "register", "address",
                                                    "type", "word_order", "scale", "offset", "unit",
                                                    "valid_min", "valid_max", "writable",
                                                    "setpoint_min", "setpoint_max",
                                                    "max_rate_per_s"}
          : std::initializer_list<std::string_view>{"name", "plc", "role", "register", "address",
                                                    "type", "word_order", "scale", "offset", "unit",
                                                    "valid_min", "valid_max", "writable"},
      ch.writable ? std::map<std::string, std::string>{}
                  : std::map<std::string, std::string>{{"setpoint_min", needs_writable},
                                                       {"setpoint_max", needs_writable},
                                                       {"max_rate_per_s", needs_writable}});
  r.String(t, at, "name", ch.name, true);
  r.String(t, at, "plc", ch.plc, true);
  r.Enum(t, at, "role", ch.role, true);
  r.Enum(t, at, "register", ch.table, true);
  r.Integer(t, at, "address", ch.address, true);
  r.Enum(t, at, "type", ch.type, true);
  r.Enum(t, at, "word_order", ch.word_order);
  r.Double(t, at, "scale", ch.scale);
  r.Double(t, at, "offset", ch.offset);
  r.String(t, at, "unit", ch.unit);
  r.Double(t, at, "valid_min", ch.valid_min);
  r.Double(t, at, "valid_max", ch.valid_max);
  if (ch.writable) {
    r.Double(t, at, "setpoint_min", ch.setpoint_min, true);
    r.Double(t, at, "setpoint_max", ch.setpoint_max, true);
    r.Double(t, at, "max_rate_per_s", ch.max_rate_per_s, true);
  }
}

void ReadReach(Reader& r, const toml::table& t, const std::string& at, ReachConfig& reach) {
  r.Keys(t, at,
         {"name",
          "inflow",
          "outflow",
          "level",
          "actuator",
          "nominal_setpoint",
          "actuator_gain_m3s_per_unit",
          "nominal_inflow_m3s",
          "expected_delay_s",
          "level_min_m",
          "level_max_m",
          "online_models",
          "min_delay_s",
          "max_delay_s",
          "forgetting",
          "initial_covariance",
          "rls_method",
          "closed_loop",
          "id_wave_front",
          "batch_models",
          "idz_p22_s_per_m2",
          "idz_p22_std_s_per_m2",
          "actuator_position",
          "arx_na",
          "arx_nb",
          "fractional_alphas",
          "fractional_delay_s",
          "lpv_scheduling",
          "lpv_na",
          "lpv_nb",
          "model_publish_period_s",
          "lpv_delay_s",
          "frac_ss_q",
          "frac_ss_delay_s"});
  r.String(t, at, "name", reach.name, true);
  r.String(t, at, "inflow", reach.inflow, true);
  r.String(t, at, "outflow", reach.outflow, true);
  r.String(t, at, "level", reach.level, true);
  r.String(t, at, "actuator", reach.actuator, true);
  r.OptionalDouble(t, at, "nominal_setpoint", reach.nominal_setpoint);
  r.OptionalDouble(t, at, "actuator_gain_m3s_per_unit", reach.actuator_gain_m3s_per_unit);
  r.Double(t, at, "nominal_inflow_m3s", reach.nominal_inflow_m3s, true);
  r.Double(t, at, "expected_delay_s", reach.expected_delay_s, true);
  r.Double(t, at, "level_min_m", reach.level_min_m, true);
  r.Double(t, at, "level_max_m", reach.level_max_m, true);
  r.EnumList(t, at, "online_models", reach.online_models);
  r.Double(t, at, "min_delay_s", reach.min_delay_s);
  // Default: twice the operators' guess, so the bank brackets it.
  reach.max_delay_s = 2.0 * reach.expected_delay_s;
  r.Double(t, at, "max_delay_s", reach.max_delay_s);
  r.Double(t, at, "forgetting", reach.forgetting);
  r.OptionalDouble(t, at, "initial_covariance", reach.initial_covariance);
  r.Enum(t, at, "rls_method", reach.rls_method);
  r.Enum(t, at, "closed_loop", reach.closed_loop);
  r.OptionalBool(t, at, "id_wave_front", reach.id_wave_front);
  r.EnumList(t, at, "batch_models", reach.batch_models);
  r.OptionalDouble(t, at, "idz_p22_s_per_m2", reach.idz_p22_s_per_m2);
  r.OptionalDouble(t, at, "idz_p22_std_s_per_m2", reach.idz_p22_std_s_per_m2);
  r.String(t, at, "actuator_position", reach.actuator_position);
  r.Integer(t, at, "arx_na", reach.arx_na);
  r.Integer(t, at, "arx_nb", reach.arx_nb);
  r.DoubleList(t, at, "fractional_alphas", reach.fractional_alphas);
  // Default: the operators' delay guess.
  reach.fractional_delay_s = reach.expected_delay_s;
  r.Double(t, at, "fractional_delay_s", reach.fractional_delay_s);
  r.String(t, at, "lpv_scheduling", reach.lpv_scheduling);
  r.Integer(t, at, "lpv_na", reach.lpv_na);
  r.Integer(t, at, "lpv_nb", reach.lpv_nb);
  reach.lpv_delay_s = reach.expected_delay_s;
  r.Double(t, at, "lpv_delay_s", reach.lpv_delay_s);
  r.Integer(t, at, "frac_ss_q", reach.frac_ss_q);
  reach.frac_ss_delay_s = reach.expected_delay_s;
  r.Double(t, at, "frac_ss_delay_s", reach.frac_ss_delay_s);
  r.Double(t, at, "model_publish_period_s", reach.model_publish_period_s);
}

void ReadExperiment(Reader& r, const toml::table& t, const std::string& at, ExperimentConfig& e) {
  r.Enum(t, at, "mode", e.mode);
  const std::string design_only = "mode = \"design\"";
  const std::string explicit_only = "mode = \"explicit\"";
  const std::string prbs_only = "mode = \"design\" or \"explicit\"";
  const std::string step_only = "mode = \"step\"";
  switch (e.mode) {
    case config::ExperimentMode::kDesign:
      r.Keys(t, at,
             {"name", "reach", "mode", "amplitude_percent", "duration_factor", "seed", "settle_s",
              "start", "max_invalid_samples", "max_sample_gap_periods", "with"},
             {{"amplitude", explicit_only},
              {"clock_period_s", explicit_only},
              {"order", explicit_only},
              {"periods", explicit_only},
              {"hold_s", step_only}});
      r.Double(t, at, "amplitude_percent", e.amplitude_percent);
      r.Double(t, at, "duration_factor", e.duration_factor);
      break;
    case config::ExperimentMode::kExplicit:
      r.Keys(t, at,
             {"name", "reach", "mode", "amplitude", "clock_period_s", "order", "periods", "seed",
              "settle_s", "start", "max_invalid_samples", "max_sample_gap_periods", "with"},
             {{"amplitude_percent", design_only},
              {"duration_factor", design_only},
              {"hold_s", step_only}});
      r.Double(t, at, "amplitude", e.amplitude, true);
      r.Double(t, at, "clock_period_s", e.clock_period_s, true);
      r.Integer(t, at, "order", e.order);
      r.Integer(t, at, "periods", e.periods);
      break;
    case config::ExperimentMode::kStep:
      r.Keys(t, at,
             {"name", "reach", "mode", "amplitude", "hold_s", "settle_s", "start",
              "max_invalid_samples", "max_sample_gap_periods", "with"},
             {{"amplitude_percent", design_only},
              {"duration_factor", design_only},
              {"clock_period_s", explicit_only},
              {"order", explicit_only},
              {"periods", explicit_only},
              {"seed", prbs_only}});
      r.Double(t, at, "amplitude", e.amplitude, true);
      r.Double(t, at, "hold_s", e.hold_s, true);
      break;
  }
  r.String(t, at, "name", e.name, true);
  r.String(t, at, "reach", e.reach, true);
  if (e.mode != config::ExperimentMode::kStep) r.Integer(t, at, "seed", e.seed);
  r.Double(t, at, "settle_s", e.settle_s);
  r.Enum(t, at, "start", e.start);
  r.Integer(t, at, "max_invalid_samples", e.max_invalid_samples);
  r.Double(t, at, "max_sample_gap_periods", e.max_sample_gap_periods);
  r.StringList(t, at, "with", e.with);
}

void ReadCommands(Reader& r, const toml::table& root, DaemonConfig& c) {
  const toml::table* t = r.Table(root, "", "commands");
  if (t == nullptr) return;
  r.Keys(*t, "commands", {"enabled", "key_file", "max_clock_skew_s", "accepted"});
  r.Bool(*t, "commands", "enabled", c.commands.enabled);
  r.String(*t, "commands", "key_file", c.commands.key_file);
  r.Double(*t, "commands", "max_clock_skew_s", c.commands.max_clock_skew_s);
  r.EnumList(*t, "commands", "accepted", c.commands.accepted);
}

DaemonConfig Parse(core::TomlReader& toml) {
  const toml::table& root = toml.root();
  Reader r(toml);
  DaemonConfig c;
  r.Keys(root, "",
         {"daemon", "lcm", "results", "plc", "channel", "reach", "experiment", "commands"});
  ReadDaemon(r, root, c);
  ReadLcm(r, root, c);
  ReadResults(r, root, c);
  r.Tables(root, "plc", [&](const toml::table& t, const std::string& at) {
    ReadPlc(r, t, at, c.plcs.emplace_back());
  });
  r.Tables(root, "channel", [&](const toml::table& t, const std::string& at) {
    ReadChannel(r, t, at, c.channels.emplace_back());
  });
  r.Tables(root, "reach", [&](const toml::table& t, const std::string& at) {
    ReadReach(r, t, at, c.reaches.emplace_back());
  });
  r.Tables(root, "experiment", [&](const toml::table& t, const std::string& at) {
    ReadExperiment(r, t, at, c.experiments.emplace_back());
  });
  ReadCommands(r, root, c);
  for (const config::ConfigProblem& problem : config::Validate(c)) r.Place(problem);
  if (toml.HasProblems()) throw ConfigError(toml.Issues());
  return c;
}

}  // namespace

DaemonConfig ParseDaemonConfig(std::string_view text, const std::string& name) {
  core::TomlReader toml(text, name);  // throws the syntax error alone
  return Parse(toml);
}

DaemonConfig LoadDaemonConfig(const std::string& path) {
  core::TomlReader toml = core::TomlReader::FromFile(path);
  return Parse(toml);
}

}  // namespace canalid::daemon
