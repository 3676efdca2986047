#include "sim/canal.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::sim {
namespace {

void Require(bool ok, const std::string& where, const char* field, double value,
             const char* range) {
  if (ok) return;
  std::ostringstream os;
  os << where << ": " << field << " = " << value << " must be " << range;
  throw std::invalid_argument(os.str());
}

}  // namespace

int FindPoolIndex(const Canal& canal, const std::string& name) {
  for (std::size_t i = 0; i < canal.pools.size(); ++i) {
    if (canal.pools[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void ValidateCanal(const Canal& canal) {
  if (canal.pools.empty()) throw std::invalid_argument("canal " + canal.name + ": no pools");
  Require(canal.max_dx_m > 0.0, "canal " + canal.name, "max_dx_m", canal.max_dx_m, "> 0");
  Require(canal.theta > 0.5 && canal.theta <= 1.0, "canal " + canal.name, "theta", canal.theta,
          "in (0.5, 1]");
  Require(std::isfinite(canal.upstream.flow_m3s) && canal.upstream.flow_m3s >= 0.0,
          "canal " + canal.name, "upstream flow_m3s", canal.upstream.flow_m3s, ">= 0");
  for (std::size_t i = 0; i < canal.pools.size(); ++i) {
    const Pool& p = canal.pools[i];
    const std::string where = "pool " + p.name;
    Require(p.length_m > 0.0, where, "length_m", p.length_m, "> 0");
    Require(p.bottom_width_m >= 0.0, where, "bottom_width_m", p.bottom_width_m, ">= 0");
    Require(p.side_slope >= 0.0, where, "side_slope", p.side_slope, ">= 0");
    Require(p.bottom_width_m + p.side_slope > 0.0, where, "bottom_width_m + side_slope",
            p.bottom_width_m + p.side_slope, "> 0");
    Require(std::isfinite(p.bed_slope) && std::abs(p.bed_slope) < 0.1, where, "bed_slope",
            p.bed_slope, "in (-0.1, 0.1)");
    Require(p.manning_n > 0.0 && p.manning_n < 1.0, where, "manning_n", p.manning_n, "in (0, 1)");
    Require(p.target_depth_m > 0.0, where, "target_depth_m", p.target_depth_m, "> 0");
    Require(p.structure.width_m > 0.0, where, "structure width_m", p.structure.width_m, "> 0");
    Require(p.structure.coefficient > 0.0, where, "structure coefficient", p.structure.coefficient,
            "> 0");
    Require(p.structure.drop_m >= 0.0, where, "structure drop_m", p.structure.drop_m, ">= 0");
    Require(std::isfinite(p.structure.setting), where, "structure setting", p.structure.setting,
            "finite");
    Require(p.offtake.setting >= 0.0, where, "offtake setting", p.offtake.setting, ">= 0");
    Require(p.offtake.coefficient > 0.0, where, "offtake coefficient", p.offtake.coefficient,
            "> 0");
  }
  for (std::size_t i = 0; i < canal.level_controls.size(); ++i) {
    const LevelControl& c = canal.level_controls[i];
    const std::string where = "level control " + c.name;
    if (FindPoolIndex(canal, c.level_pool) < 0) {
      throw std::invalid_argument(where + ": level pool '" + c.level_pool +
                                  "' is not in the canal");
    }
    if (c.actuator_pool.empty()) {
      if (canal.upstream.type != UpstreamBoundary::Type::kFlow) {
        throw std::invalid_argument(where +
                                    ": the upstream inflow is its pump, so [upstream] type must "
                                    "be \"flow\"");
      }
    } else {
      const int a = FindPoolIndex(canal, c.actuator_pool);
      if (a < 0 ||
          canal.pools[static_cast<std::size_t>(a)].structure.type != Structure::Type::kPump) {
        throw std::invalid_argument(where + ": actuator pool '" + c.actuator_pool +
                                    "' must be a pool of the canal whose structure is a pump");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (canal.level_controls[j].actuator_pool == c.actuator_pool) {
        throw std::invalid_argument(where + ": its pump is already driven by level control " +
                                    canal.level_controls[j].name);
      }
    }
    try {
      LevelPid check(c.pid);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
}

}  // namespace canalid::sim
