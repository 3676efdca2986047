#include "sim/scenario.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "sim/canal_config.h"
#include "sim/config_reader.h"
#include "sim/hydraulics.h"

namespace canalid::sim {
namespace {

constexpr double kBig = 1e9;

int FindPool(const Canal& canal, const std::string& name) {
  for (std::size_t i = 0; i < canal.pools.size(); ++i) {
    if (canal.pools[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::string PoolNames(const Canal& canal) {
  std::string names;
  for (const Pool& p : canal.pools) names += (names.empty() ? "" : ", ") + p.name;
  return names;
}

// "inflow" or "pool<name>.structure" / "pool<name>.offtake".
bool ParseInput(const Canal& canal, const std::string& text, InputRef* ref) {
  if (text == "inflow" || text == "upstream") {
    ref->kind = InputRef::Kind::kUpstream;
    return true;
  }
  const std::size_t dot = text.rfind('.');
  if (text.rfind("pool", 0) != 0 || dot == std::string::npos) return false;
  ref->pool = FindPool(canal, text.substr(4, dot - 4));
  const std::string what = text.substr(dot + 1);
  if (ref->pool < 0) return false;
  if (what == "structure") {
    ref->kind = InputRef::Kind::kStructure;
  } else if (what == "offtake") {
    ref->kind = InputRef::Kind::kOfftake;
  } else {
    return false;
  }
  return true;
}

bool ParseOutput(const Canal& canal, const std::string& text, OutputRef* ref) {
  const std::size_t dot = text.rfind('.');
  if (text.rfind("pool", 0) != 0 || dot == std::string::npos) return false;
  ref->pool = FindPool(canal, text.substr(4, dot - 4));
  if (ref->pool < 0) return false;
  const std::string what = text.substr(dot + 1);
  using K = OutputRef::Kind;
  if (what == "inflow") {
    ref->kind = K::kInflow;
  } else if (what == "outflow") {
    ref->kind = K::kOutflow;
  } else if (what == "level_upstream") {
    ref->kind = K::kLevelUpstream;
  } else if (what == "level_downstream") {
    ref->kind = K::kLevelDownstream;
  } else if (what == "volume") {
    ref->kind = K::kVolume;
  } else if (what == "structure_flow") {
    ref->kind = K::kStructureFlow;
  } else if (what == "structure_setting") {
    ref->kind = K::kStructureSetting;
  } else if (what == "offtake_flow") {
    ref->kind = K::kOfftakeFlow;
  } else {
    return false;
  }
  return true;
}

SensorConfig ReadSensor(ConfigReader& reader, const toml::table& t, const std::string& where) {
  reader.CheckKeys(
      t, where,
      {"noise_std", "quantum", "spike_rate_per_h", "spike_min", "spike_max", "drift_per_h",
       "stuck_rate_per_h", "stuck_duration_s", "dropout_rate_per_h", "dropout_duration_s"});
  SensorConfig s;
  s.noise_std = reader.Number(t, "noise_std", where, 0.0, 0.0, kBig);
  s.quantum = reader.Number(t, "quantum", where, 0.0, 0.0, kBig);
  s.spike_rate_per_h = reader.Number(t, "spike_rate_per_h", where, 0.0, 0.0, 3600.0);
  s.spike_min = reader.Number(t, "spike_min", where, 0.0, 0.0, kBig);
  s.spike_max = reader.Number(t, "spike_max", where, s.spike_min, s.spike_min, kBig);
  s.drift_per_h = reader.Number(t, "drift_per_h", where, 0.0, -kBig, kBig);
  s.stuck_rate_per_h = reader.Number(t, "stuck_rate_per_h", where, 0.0, 0.0, 3600.0);
  s.stuck_duration_s = reader.Number(t, "stuck_duration_s", where, 0.0, 0.0, kBig);
  s.dropout_rate_per_h = reader.Number(t, "dropout_rate_per_h", where, 0.0, 0.0, 3600.0);
  s.dropout_duration_s = reader.Number(t, "dropout_duration_s", where, 0.0, 0.0, kBig);
  return s;
}

}  // namespace

namespace {

std::string UnknownTargetProblem(const std::string& where, const std::string& target,
                                 const Canal& canal) {
  return "'" + where + ".target' = \"" + target +
         "\" must be \"inflow\", \"pool<name>.structure\" or \"pool<name>.offtake\" with a "
         "simulated pool (" +
         PoolNames(canal) + ")";
}

std::string ControlledTargetProblem(const std::string& where, const std::string& target,
                                    const LevelControl& control) {
  return "'" + where + ".target' = \"" + target + "\" is the pump of level control " +
         control.name + ", which sets it";
}

Scenario ReadScenario(ConfigReader& reader, const Canal& full) {
  const toml::table& root = reader.root();
  reader.CheckKeys(
      root, "",
      {"duration_s", "output_period_s", "time_step_s", "seed", "first_pool", "last_pool",
       "inflow_m3s", "max_dx_m", "theta", "pools", "event", "output", "sensor"});
  Scenario sc;
  sc.duration_s = reader.Number(root, "duration_s", "", std::nullopt, 1e-3, 1e9);
  sc.output_period_s = reader.Number(root, "output_period_s", "", std::nullopt, 1e-3, 1e7);
  sc.time_step_s = reader.Number(root, "time_step_s", "", sc.output_period_s, 1e-3, 1e5);
  sc.seed = static_cast<std::uint64_t>(reader.Integer(root, "seed", "", 1, 0, 4000000000));
  if (sc.output_period_s > 0.0 && sc.time_step_s > 0.0) {
    const double ratio = sc.output_period_s / sc.time_step_s;
    if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio || std::round(ratio) < 1.0) {
      reader.Problem(root.source(), "'output_period_s' must be a whole multiple of 'time_step_s'");
    }
  }

  // Pool range.
  const std::string first = reader.String(root, "first_pool", "", full.pools.front().name);
  const std::string last = reader.String(root, "last_pool", "", full.pools.back().name);
  int i0 = FindPool(full, first);
  int i1 = FindPool(full, last);
  if (i0 < 0 || i1 < 0 || i1 < i0) {
    reader.Problem(root.source(), "first_pool \"" + first + "\" and last_pool \"" + last +
                                      "\" must name pools in order among: " + PoolNames(full));
    i0 = 0;
    i1 = static_cast<int>(full.pools.size()) - 1;
  }
  sc.canal = full;
  sc.canal.pools.assign(full.pools.begin() + i0, full.pools.begin() + i1 + 1);
  double inflow = full.upstream.flow_m3s;
  for (int i = 0; i < i0; ++i) {
    const Pool& p = full.pools[static_cast<std::size_t>(i)];
    inflow -= OfftakeFlow(p.offtake, p.offtake.setting, p.target_depth_m);
  }
  if (i0 > 0) sc.canal.upstream.type = UpstreamBoundary::Type::kFlow;
  // Level loops come along only when both their level and their pump are simulated.
  std::erase_if(sc.canal.level_controls, [&](const LevelControl& c) {
    const bool pump_in =
        c.actuator_pool.empty() ? i0 == 0 : FindPool(sc.canal, c.actuator_pool) >= 0;
    return !pump_in || FindPool(sc.canal, c.level_pool) < 0;
  });
  sc.canal.upstream.flow_m3s = reader.Number(root, "inflow_m3s", "", inflow, 0.0, 1e5);
  sc.canal.max_dx_m = reader.Number(root, "max_dx_m", "", full.max_dx_m, 0.01, 1e4);
  sc.canal.theta = reader.Number(root, "theta", "", full.theta, 0.5000001, 1.0);

  // Per-pool overrides.
  if (const toml::node* node = root.get("pools")) {
    if (const toml::table* pools = node->as_table()) {
      for (const auto& [key, value] : *pools) {
        const std::string where = "pools." + std::string(key.str());
        const int i = FindPool(sc.canal, std::string(key.str()));
        const toml::table* t = value.as_table();
        if (i < 0 || t == nullptr) {
          reader.Problem(value.source(), "'" + where +
                                             "' must be a table named after a simulated "
                                             "pool (" +
                                             PoolNames(sc.canal) + ")");
          continue;
        }
        Pool& p = sc.canal.pools[static_cast<std::size_t>(i)];
        reader.CheckKeys(*t, where, {"target_depth_m", "structure", "offtake"});
        p.target_depth_m =
            reader.Number(*t, "target_depth_m", where, p.target_depth_m, 1e-3, 100.0);
        if (const toml::table* s = (*t)["structure"].as_table()) {
          ReadStructure(reader, *s, where + ".structure", &p.structure);
        }
        if (const toml::table* o = (*t)["offtake"].as_table()) {
          ReadOfftake(reader, *o, where + ".offtake", &p.offtake);
        }
      }
    } else {
      reader.Problem(node->source(), "'pools' must be a table");
    }
  }

  // Events.
  if (const toml::node* node = root.get("event")) {
    const toml::array* events = node->as_array();
    if (events == nullptr) reader.Problem(node->source(), "'event' must be an array of tables");
    for (std::size_t k = 0; events != nullptr && k < events->size(); ++k) {
      const std::string where = "event[" + std::to_string(k) + "]";
      const toml::table* t = reader.TableAt(*events, k, where);
      if (t == nullptr) continue;
      reader.CheckKeys(
          *t, where,
          {"time_s", "target", "kind", "value", "amplitude", "clock_s", "order", "seed", "end_s"});
      Event e;
      e.time_s = reader.Number(*t, "time_s", where, std::nullopt, 0.0, 1e9);
      const std::string target = reader.String(*t, "target", where, std::nullopt);
      const bool parsed = ParseInput(sc.canal, target, &e.input);
      if (!parsed) {
        reader.Problem(t->get("target") != nullptr ? t->get("target")->source() : t->source(),
                       UnknownTargetProblem(where, target, sc.canal));
      }
      for (const LevelControl& c : sc.canal.level_controls) {
        if (!parsed) break;
        const bool owned = c.actuator_pool.empty()
                               ? e.input.kind == InputRef::Kind::kUpstream
                               : e.input.kind == InputRef::Kind::kStructure &&
                                     sc.canal.pools[static_cast<std::size_t>(e.input.pool)].name ==
                                         c.actuator_pool;
        if (owned) {
          reader.Problem(t->source(), ControlledTargetProblem(where, target, c));
        }
      }
      const std::string kind =
          reader.Choice(*t, "kind", where, std::nullopt, {"set", "step", "prbs"});
      if (kind == "prbs") {
        e.kind = Event::Kind::kPrbs;
        e.amplitude = reader.Number(*t, "amplitude", where, std::nullopt, 0.0, kBig);
        e.clock_s = reader.Number(*t, "clock_s", where, std::nullopt, 1e-3, kBig);
        e.order = static_cast<int>(reader.Integer(*t, "order", where, 7, 2, 16));
        e.seed = static_cast<std::uint64_t>(
            reader.Integer(*t, "seed", where, static_cast<std::int64_t>(sc.seed), 0, 4000000000));
        e.end_s = reader.Number(*t, "end_s", where, std::numeric_limits<double>::infinity(),
                                e.time_s, std::numeric_limits<double>::infinity());
      } else if (kind == "set" || kind == "step") {
        e.kind = kind == "set" ? Event::Kind::kSet : Event::Kind::kStep;
        e.value = reader.Number(*t, "value", where, std::nullopt, -kBig, kBig);
      }
      sc.events.push_back(e);
    }
  }

  // Output columns and their sensors.
  const toml::table* output = root["output"].as_table();
  if (output == nullptr || output->empty()) {
    reader.Problem(root.source(), "missing table [output] with at least one column");
  } else {
    // toml++ tables are ordered by key; the CSV keeps the order of the file.
    std::vector<std::pair<toml::source_position, OutputColumn>> ordered;
    for (const auto& [key, value] : *output) {
      OutputColumn c;
      c.name = std::string(key.str());
      if (c.name == "time_s" || c.name.find_first_of(",\"\n") != std::string::npos) {
        reader.Problem(value.source(), "output column name '" + c.name +
                                           "' is reserved or "
                                           "contains a comma, quote or newline");
      }
      if (!value.is_string()) {
        reader.Problem(value.source(), "'output." + c.name + "' must be a string");
        continue;
      }
      c.variable = std::string(*value.value<std::string_view>());
      if (!ParseOutput(sc.canal, c.variable, &c.ref)) {
        reader.Problem(value.source(),
                       "'output." + c.name + "' = \"" + c.variable +
                           "\" must be \"pool<name>.<inflow|outflow|level_upstream|"
                           "level_downstream|volume|structure_flow|structure_setting|"
                           "offtake_flow>\" with a simulated pool (" +
                           PoolNames(sc.canal) + ")");
      }
      ordered.emplace_back(value.source().begin, c);
    }
    std::stable_sort(ordered.begin(), ordered.end(), [](const auto& a, const auto& b) {
      return a.first.line != b.first.line ? a.first.line < b.first.line
                                          : a.first.column < b.first.column;
    });
    for (auto& [position, column] : ordered) sc.columns.push_back(column);
  }
  if (const toml::node* node = root.get("sensor")) {
    if (const toml::table* sensors = node->as_table()) {
      for (const auto& [key, value] : *sensors) {
        const std::string where = "sensor." + std::string(key.str());
        OutputColumn* column = nullptr;
        for (OutputColumn& c : sc.columns) {
          if (c.name == key.str()) column = &c;
        }
        const toml::table* t = value.as_table();
        if (column == nullptr || t == nullptr) {
          reader.Problem(value.source(), "'" + where +
                                             "' must be a table named after an output "
                                             "column");
          continue;
        }
        column->sensor = ReadSensor(reader, *t, where);
      }
    } else {
      reader.Problem(node->source(), "'sensor' must be a table");
    }
  }
  reader.FinishValidated([&] { ValidateCanal(sc.canal); });
  return sc;
}

}  // namespace

Scenario LoadScenario(const std::string& path, const Canal& canal) {
  ConfigReader reader(path);
  return ReadScenario(reader, canal);
}

Scenario ParseScenario(std::string_view text, const std::string& name, const Canal& canal) {
  ConfigReader reader = ConfigReader::FromText(text, name);
  return ReadScenario(reader, canal);
}

}  // namespace canalid::sim
