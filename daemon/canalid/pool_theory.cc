#include "daemon/canalid/pool_theory.h"

#include <sstream>
#include <stdexcept>

#include "daemon/canalid/input_error.h"
#include "sim/canal_config.h"

namespace canalid::cli {

core::IdzTheory PoolTheory(const std::string& canal_file, const std::string& pool,
                           double flow_m3s) {
  sim::Canal canal;
  try {
    canal = sim::LoadCanal(canal_file);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  std::string names;
  for (const sim::Pool& p : canal.pools) {
    names += (names.empty() ? "" : ", ") + p.name;
    if (p.name != pool) continue;
    const core::PoolGeometry geometry{p.length_m,  p.bottom_width_m, p.side_slope,
                                      p.bed_slope, p.manning_n,      p.target_depth_m};
    try {
      return core::IdzFromGeometry(geometry, flow_m3s);
    } catch (const std::invalid_argument& e) {
      std::ostringstream os;
      os << canal_file << ": pool " << p.name << " at " << flow_m3s << " m3/s: " << e.what();
      throw InputError(os.str());
    }
  }
  throw InputError("--pool '" + pool + "' is not a pool of " + canal_file + " (pools: " + names +
                   ")");
}

}  // namespace canalid::cli
