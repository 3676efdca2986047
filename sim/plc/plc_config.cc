#include "sim/plc/plc_config.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sim/config_reader.h"
#include "sim/plc/register_map.h"

namespace canalid::sim::plc {
namespace {

constexpr double kMaxAddress = 65535.0;

// Range of setpoints that no sensible command leaves, for a pool of `canal`.
void DefaultLimits(const Canal& canal, int index, PoolPlcConfig* p) {
  const Pool& pool = canal.pools.at(static_cast<std::size_t>(index));
  const double big_flow_m3s = 5.0 * std::max(canal.upstream.flow_m3s, 1.0);
  p->name = pool.name;
  p->pool = index;
  p->setpoint_min = 0.0;
  p->setpoint_max = pool.structure.type == Structure::Type::kPump
                        ? big_flow_m3s
                        : std::max(pool.bank_depth_m, 2.0 * pool.target_depth_m);
  p->rate_per_s = 0.0;
  p->offtake_min = 0.0;
  p->offtake_max = big_flow_m3s;
}

int Address(ConfigReader& reader, const toml::table& t, std::string_view key,
            std::string_view where, int fallback) {
  const double value = reader.Number(t, key, where, fallback, 0.0, kMaxAddress);
  if (value != std::floor(value)) {
    reader.Problem(t.get(key)->source(), "'" + KeyPath(where, key) + "' must be an integer");
  }
  return static_cast<int>(value);
}

struct Block {
  const char* name;
  int first;
  int count;
};

void CheckBlocks(const char* kind, const std::vector<Block>& blocks) {
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    if (blocks[i].first + blocks[i].count > 65536) {
      throw std::invalid_argument(std::string(blocks[i].name) + " = " +
                                  std::to_string(blocks[i].first) + " runs past address 65535");
    }
    for (std::size_t j = i + 1; j < blocks.size(); ++j) {
      const Block& a = blocks[i];
      const Block& b = blocks[j];
      if (a.count > 0 && b.count > 0 && a.first < b.first + b.count &&
          b.first < a.first + a.count) {
        std::ostringstream os;
        os << kind << " blocks overlap: " << a.name << " [" << a.first << ", " << a.first + a.count
           << ") and " << b.name << " [" << b.first << ", " << b.first + b.count << ")";
        throw std::invalid_argument(os.str());
      }
    }
  }
}

}  // namespace

PlcConfig DefaultPlcConfig(const Canal& canal) {
  PlcConfig config;
  config.upstream_min_m3s = 0.0;
  config.upstream_max_m3s = 5.0 * std::max(canal.upstream.flow_m3s, 1.0);
  for (int i = 0; i < static_cast<int>(canal.pools.size()); ++i) {
    PoolPlcConfig p;
    DefaultLimits(canal, i, &p);
    config.pools.push_back(p);
  }
  return config;
}

void ValidatePlcConfig(const PlcConfig& c) {
  auto demand = [](bool ok, const std::string& what, double value, const char* range) {
    if (!ok) {
      std::ostringstream os;
      os << what << " = " << value << " must be " << range;
      throw std::invalid_argument(os.str());
    }
  };
  demand(c.plant_step_s > 0.0 && c.plant_step_s <= 3600.0, "plant_step_s", c.plant_step_s,
         "in (0, 3600]");
  demand(c.heartbeat_timeout_s >= 0.0, "heartbeat_timeout_s", c.heartbeat_timeout_s, ">= 0");
  demand(c.level_unit_m > 0.0, "level_unit_m", c.level_unit_m, "> 0");
  demand(c.flow_unit_m3s > 0.0, "flow_unit_m3s", c.flow_unit_m3s, "> 0");
  demand(c.setting_unit_m > 0.0, "setting_unit_m", c.setting_unit_m, "> 0");
  demand(c.area_unit_m2 > 0.0, "area_unit_m2", c.area_unit_m2, "> 0");
  demand(c.upstream_min_m3s <= c.upstream_max_m3s, "upstream max_flow_m3s", c.upstream_max_m3s,
         ">= min_flow_m3s");
  demand(c.upstream_rate_m3s_per_s >= 0.0, "upstream rate_m3s_per_s", c.upstream_rate_m3s_per_s,
         ">= 0");
  demand(!c.pools.empty() && c.pools.size() <= 16, "number of pools",
         static_cast<double>(c.pools.size()), "in [1, 16] (the fault masks have 16 bits)");
  for (const PoolPlcConfig& p : c.pools) {
    const std::string where = "pool '" + p.name + "' ";
    demand(p.setpoint_min <= p.setpoint_max, where + "setpoint_max", p.setpoint_max,
           ">= setpoint_min");
    demand(p.offtake_min <= p.offtake_max, where + "offtake_max", p.offtake_max, ">= offtake_min");
    demand(p.rate_per_s >= 0.0, where + "rate_per_s", p.rate_per_s, ">= 0");
  }
  const int n = static_cast<int>(c.pools.size());
  CheckBlocks("input register",
              {{"system", 0, kIrSystemSize},
               {"input_scaled_base", c.input_scaled_base, n * kPoolInputFields},
               {"input_float_base", c.input_float_base, 2 * n * kPoolInputFields}});
  CheckBlocks("holding register",
              {{"system", 0, kHrSystemSize},
               {"holding_scaled_base", c.holding_scaled_base, n * kPoolHoldingFields},
               {"holding_float_base", c.holding_float_base, 2 * n * kPoolHoldingFields}});
}

namespace {

PlcConfig ReadPlcConfig(ConfigReader& reader, const Canal& canal) {
  const toml::table& root = reader.root();
  PlcConfig c = DefaultPlcConfig(canal);
  c.pools.clear();
  reader.CheckKeys(root, "",
                   {"plant_step_s", "heartbeat_timeout_s", "registers", "upstream", "pool"});
  c.plant_step_s = reader.Number(root, "plant_step_s", "", c.plant_step_s, 1e-3, 3600.0);
  c.heartbeat_timeout_s =
      reader.Number(root, "heartbeat_timeout_s", "", c.heartbeat_timeout_s, 0.0, 1e7);
  if (const toml::node* node = root.get("registers")) {
    if (const toml::table* t = node->as_table()) {
      const std::string w = "registers";
      reader.CheckKeys(
          *t, w,
          {"float_word_order", "level_unit_m", "flow_unit_m3s", "setting_unit_m", "area_unit_m2",
           "input_scaled_base", "input_float_base", "holding_scaled_base", "holding_float_base"});
      const std::string order =
          reader.Choice(*t, "float_word_order", w, "abcd", {"abcd", "cdab", "badc", "dcba"});
      c.word_order = core::WordOrderFromLetters(order).value_or(c.word_order);
      c.level_unit_m = reader.Number(*t, "level_unit_m", w, c.level_unit_m, 1e-6, 10.0);
      c.flow_unit_m3s = reader.Number(*t, "flow_unit_m3s", w, c.flow_unit_m3s, 1e-6, 10.0);
      c.setting_unit_m = reader.Number(*t, "setting_unit_m", w, c.setting_unit_m, 1e-6, 10.0);
      c.area_unit_m2 = reader.Number(*t, "area_unit_m2", w, c.area_unit_m2, 1e-8, 10.0);
      c.input_scaled_base = Address(reader, *t, "input_scaled_base", w, c.input_scaled_base);
      c.input_float_base = Address(reader, *t, "input_float_base", w, c.input_float_base);
      c.holding_scaled_base = Address(reader, *t, "holding_scaled_base", w, c.holding_scaled_base);
      c.holding_float_base = Address(reader, *t, "holding_float_base", w, c.holding_float_base);
    } else {
      reader.Problem(node->source(), "'registers' must be a table");
    }
  }
  if (const toml::node* node = root.get("upstream")) {
    if (const toml::table* t = node->as_table()) {
      const std::string w = "upstream";
      reader.CheckKeys(*t, w, {"min_flow_m3s", "max_flow_m3s", "rate_m3s_per_s"});
      c.upstream_min_m3s = reader.Number(*t, "min_flow_m3s", w, c.upstream_min_m3s, 0.0, 1e5);
      c.upstream_max_m3s = reader.Number(*t, "max_flow_m3s", w, c.upstream_max_m3s, 0.0, 1e5);
      c.upstream_rate_m3s_per_s =
          reader.Number(*t, "rate_m3s_per_s", w, c.upstream_rate_m3s_per_s, 0.0, 1e5);
      if (c.upstream_min_m3s > c.upstream_max_m3s) {
        reader.Problem(t->source(), "'upstream.min_flow_m3s' is above 'upstream.max_flow_m3s'");
      }
    } else {
      reader.Problem(node->source(), "'upstream' must be a table");
    }
  }
  const toml::array* pools = root["pool"].as_array();
  if (pools == nullptr || pools->empty()) {
    reader.Problem(root.source(), "missing [[pool]] entries");
  } else {
    for (std::size_t i = 0; i < pools->size(); ++i) {
      const std::string w = "pool[" + std::to_string(i) + "]";
      const toml::table* t = reader.TableAt(*pools, i, w);
      if (t == nullptr) continue;
      reader.CheckKeys(
          *t, w,
          {"name", "setpoint_min", "setpoint_max", "rate_per_s", "offtake_min", "offtake_max"});
      const std::string name = reader.String(*t, "name", w, std::nullopt);
      const auto it = std::find_if(canal.pools.begin(), canal.pools.end(),
                                   [&](const Pool& p) { return p.name == name; });
      if (it == canal.pools.end()) {
        const toml::node* n = t->get("name");
        if (n != nullptr) {
          reader.Problem(n->source(), "'" + KeyPath(w, "name") + "' = \"" + name +
                                          "\" is not a pool of canal '" + canal.name + "'");
        }
        continue;
      }
      PoolPlcConfig p;
      DefaultLimits(canal, static_cast<int>(it - canal.pools.begin()), &p);
      constexpr double kBig = 1e5;
      p.setpoint_min = reader.Number(*t, "setpoint_min", w, p.setpoint_min, -kBig, kBig);
      p.setpoint_max = reader.Number(*t, "setpoint_max", w, p.setpoint_max, -kBig, kBig);
      p.rate_per_s = reader.Number(*t, "rate_per_s", w, p.rate_per_s, 0.0, kBig);
      p.offtake_min = reader.Number(*t, "offtake_min", w, p.offtake_min, 0.0, kBig);
      p.offtake_max = reader.Number(*t, "offtake_max", w, p.offtake_max, 0.0, kBig);
      if (p.setpoint_min > p.setpoint_max) {
        reader.Problem(t->source(), "'" + w + ".setpoint_min' is above its setpoint_max");
      }
      if (p.offtake_min > p.offtake_max) {
        reader.Problem(t->source(), "'" + w + ".offtake_min' is above its offtake_max");
      }
      c.pools.push_back(p);
    }
  }
  reader.FinishValidated([&] { ValidatePlcConfig(c); });
  return c;
}

}  // namespace

PlcConfig LoadPlcConfig(const std::string& path, const Canal& canal) {
  ConfigReader reader(path);
  return ReadPlcConfig(reader, canal);
}

PlcConfig ParsePlcConfig(std::string_view text, const std::string& name, const Canal& canal) {
  ConfigReader reader = ConfigReader::FromText(text, name);
  return ReadPlcConfig(reader, canal);
}

}  // namespace canalid::sim::plc
