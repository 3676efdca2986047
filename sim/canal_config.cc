#include "sim/canal_config.h"

#include <limits>
#include <stdexcept>

namespace canalid::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const toml::table* SubTable(ConfigReader& reader, const toml::table& table, std::string_view key,
                            const std::string& where) {
  const toml::node* node = table.get(key);
  if (node == nullptr) return nullptr;
  if (!node->is_table()) {
    reader.Problem(node->source(), "'" + KeyPath(where, key) + "' must be a table");
    return nullptr;
  }
  return node->as_table();
}

// "pool<name>.level_downstream" or "pool<name>.level_upstream".
bool ParseLevel(const std::string& text, LevelControl* c) {
  for (const char* end : {".level_downstream", ".level_upstream"}) {
    const std::string suffix(end);
    if (text.size() > 4 + suffix.size() && text.rfind("pool", 0) == 0 &&
        text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0) {
      c->level_pool = text.substr(4, text.size() - 4 - suffix.size());
      c->level_downstream = suffix == ".level_downstream";
      return true;
    }
  }
  return false;
}

// "inflow" or "pool<name>.structure".
bool ParsePump(const std::string& text, LevelControl* c) {
  if (text == "inflow") {
    c->actuator_pool.clear();
    return true;
  }
  const std::string suffix = ".structure";
  if (text.size() > 4 + suffix.size() && text.rfind("pool", 0) == 0 &&
      text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0) {
    c->actuator_pool = text.substr(4, text.size() - 4 - suffix.size());
    return true;
  }
  return false;
}

void ReadLevelControl(ConfigReader& reader, const toml::table& t, const std::string& where,
                      LevelControl* c) {
  reader.CheckKeys(t, where,
                   {"name", "level", "pump", "setpoint_m", "kp", "ki", "kd", "min_flow_m3s",
                    "max_flow_m3s", "sample_time_s"});
  c->name = reader.String(t, "name", where, c->name);
  const std::string level = reader.String(t, "level", where, std::nullopt);
  if (!level.empty() && !ParseLevel(level, c)) {
    reader.Problem(t.get("level")->source(), "'" + KeyPath(where, "level") + "' = \"" + level +
                                                 "\" must be \"pool<name>.level_downstream\" "
                                                 "or \"pool<name>.level_upstream\"");
  }
  const std::string pump = reader.String(t, "pump", where, "inflow");
  if (!ParsePump(pump, c)) {
    reader.Problem(t.get("pump")->source(), "'" + KeyPath(where, "pump") + "' = \"" + pump +
                                                "\" must be \"inflow\" or "
                                                "\"pool<name>.structure\"");
  }
  LevelPidConfig& p = c->pid;
  p.setpoint_m = reader.Number(t, "setpoint_m", where, std::nullopt, 0.0, 100.0);
  p.kp = reader.Number(t, "kp", where, 0.0, 0.0, 1e6);
  p.ki = reader.Number(t, "ki", where, 0.0, 0.0, 1e6);
  p.kd = reader.Number(t, "kd", where, 0.0, 0.0, 1e6);
  p.min_flow_m3s = reader.Number(t, "min_flow_m3s", where, 0.0, 0.0, 1e5);
  p.max_flow_m3s = reader.Number(t, "max_flow_m3s", where, std::nullopt, 0.0, 1e5);
  p.sample_time_s = reader.Number(t, "sample_time_s", where, std::nullopt, 1e-4, 1e5);
}

}  // namespace

void ReadStructure(ConfigReader& reader, const toml::table& t, const std::string& where,
                   Structure* s) {
  reader.CheckKeys(t, where,
                   {"type", "width_m", "coefficient", "setting", "drop_m", "tailwater_m"});
  const char* old_type = s->type == Structure::Type::kWeir   ? "weir"
                         : s->type == Structure::Type::kPump ? "pump"
                                                             : "gate";
  const std::string type = reader.Choice(t, "type", where, old_type, {"gate", "weir", "pump"});
  s->type = type == "weir"   ? Structure::Type::kWeir
            : type == "pump" ? Structure::Type::kPump
                             : Structure::Type::kUndershotGate;
  s->width_m = reader.Number(t, "width_m", where, s->width_m, 1e-3, 1e3);
  s->coefficient = reader.Number(t, "coefficient", where, s->coefficient, 1e-3, 10.0);
  s->drop_m = reader.Number(t, "drop_m", where, s->drop_m, 0.0, 100.0);
  s->tailwater_m = reader.Number(t, "tailwater_m", where, s->tailwater_m, -kInf, 100.0);
  if (const toml::node* node = t.get("setting")) {
    if (node->is_string()) {
      if (node->value<std::string_view>() != "steady") {
        reader.Problem(node->source(),
                       "'" + KeyPath(where, "setting") + "' must be a number or \"steady\"");
      }
      s->setting_from_steady_state = true;
    } else {
      s->setting = reader.Number(t, "setting", where, 0.0, -100.0, 1e4);
      s->setting_from_steady_state = false;
    }
  }
}

void ReadOfftake(ConfigReader& reader, const toml::table& t, const std::string& where, Offtake* o) {
  reader.CheckKeys(t, where, {"type", "setting", "coefficient", "outlet_m"});
  const char* old_type = o->type == Offtake::Type::kFixedFlow ? "fixed"
                         : o->type == Offtake::Type::kOrifice ? "orifice"
                                                              : "none";
  const std::string type = reader.Choice(t, "type", where, old_type, {"none", "fixed", "orifice"});
  o->type = type == "fixed"     ? Offtake::Type::kFixedFlow
            : type == "orifice" ? Offtake::Type::kOrifice
                                : Offtake::Type::kNone;
  o->setting = reader.Number(t, "setting", where, o->setting, 0.0, 1e4);
  o->coefficient = reader.Number(t, "coefficient", where, o->coefficient, 1e-3, 10.0);
  o->outlet_m = reader.Number(t, "outlet_m", where, o->outlet_m, 0.0, 100.0);
}

namespace {

Canal ReadCanal(ConfigReader& reader) {
  const std::string& path = reader.path();
  const toml::table& root = reader.root();
  Canal canal;
  reader.CheckKeys(root, "", {"name", "max_dx_m", "theta", "upstream", "pool", "level_control"});
  canal.name = reader.String(root, "name", "", path);
  canal.max_dx_m = reader.Number(root, "max_dx_m", "", 100.0, 0.01, 1e4);
  canal.theta = reader.Number(root, "theta", "", 0.6, 0.5000001, 1.0);
  if (const toml::table* up = SubTable(reader, root, "upstream", "upstream")) {
    reader.CheckKeys(*up, "upstream", {"type", "flow_m3s"});
    canal.upstream.type =
        reader.Choice(*up, "type", "upstream", "flow", {"flow", "level"}) == "level"
            ? UpstreamBoundary::Type::kLevel
            : UpstreamBoundary::Type::kFlow;
    canal.upstream.flow_m3s = reader.Number(*up, "flow_m3s", "upstream", std::nullopt, 0.0, 1e5);
  } else {
    reader.Problem(root.source(), "missing table [upstream]");
  }
  const toml::array* pools = root["pool"].as_array();
  if (pools == nullptr || pools->empty()) {
    reader.Problem(root.source(), "missing [[pool]] entries");
  } else {
    for (std::size_t i = 0; i < pools->size(); ++i) {
      const std::string where = "pool[" + std::to_string(i) + "]";
      const toml::table* t = reader.TableAt(*pools, i, where);
      if (t == nullptr) continue;
      reader.CheckKeys(*t, where,
                       {"name", "length_m", "bottom_width_m", "side_slope", "bed_slope",
                        "manning_n", "bank_depth_m", "target_depth_m", "structure", "offtake"});
      Pool p;
      p.name = reader.String(*t, "name", where, std::to_string(i + 1));
      p.length_m = reader.Number(*t, "length_m", where, std::nullopt, 0.01, 1e6);
      p.bottom_width_m = reader.Number(*t, "bottom_width_m", where, std::nullopt, 0.0, 1e3);
      p.side_slope = reader.Number(*t, "side_slope", where, std::nullopt, 0.0, 100.0);
      p.bed_slope = reader.Number(*t, "bed_slope", where, std::nullopt, -0.1, 0.1);
      p.manning_n = reader.Number(*t, "manning_n", where, std::nullopt, 1e-4, 1.0);
      p.bank_depth_m = reader.Number(*t, "bank_depth_m", where, 0.0, 0.0, 100.0);
      p.target_depth_m = reader.Number(*t, "target_depth_m", where, std::nullopt, 1e-3, 100.0);
      p.structure.width_m = p.bottom_width_m > 0.0 ? p.bottom_width_m : 1.0;
      if (const toml::table* s = SubTable(reader, *t, "structure", where + ".structure")) {
        ReadStructure(reader, *s, where + ".structure", &p.structure);
      }
      if (const toml::table* o = SubTable(reader, *t, "offtake", where + ".offtake")) {
        ReadOfftake(reader, *o, where + ".offtake", &p.offtake);
      }
      canal.pools.push_back(p);
    }
  }
  if (const toml::node* node = root.get("level_control")) {
    const toml::array* controls = node->as_array();
    if (controls == nullptr) {
      reader.Problem(node->source(),
                     "'level_control' must be an array of tables ([[level_control]])");
    }
    for (std::size_t i = 0; controls != nullptr && i < controls->size(); ++i) {
      const std::string where = "level_control[" + std::to_string(i) + "]";
      const toml::table* t = reader.TableAt(*controls, i, where);
      if (t == nullptr) continue;
      LevelControl c;
      c.name = std::to_string(i + 1);
      ReadLevelControl(reader, *t, where, &c);
      canal.level_controls.push_back(c);
    }
  }
  reader.FinishValidated([&] { ValidateCanal(canal); });
  return canal;
}

}  // namespace

Canal LoadCanal(const std::string& path) {
  ConfigReader reader(path);
  return ReadCanal(reader);
}

Canal ParseCanal(std::string_view text, const std::string& name) {
  ConfigReader reader = ConfigReader::FromText(text, name);
  return ReadCanal(reader);
}

}  // namespace canalid::sim
