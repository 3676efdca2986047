#include "daemon/canalid/pool_theory.h"

#include <sstream>
#include <stdexcept>

#include "daemon/canalid/input_error.h"
#include "sim/canal_config.h"

namespace canalid::cli {

core::PoolGeometry GeometryOf(const sim::Pool& pool) {
  return core::PoolGeometry{pool.length_m,  pool.bottom_width_m, pool.side_slope,
                            pool.bed_slope, pool.manning_n,      pool.target_depth_m};
}

core::IdzTheory TheoryOf(const std::string& canal_file, const sim::Pool& pool, double flow_m3s) {
  try {
    return core::IdzFromGeometry(GeometryOf(pool), flow_m3s);
  } catch (const std::invalid_argument& e) {
    std::ostringstream os;
    os << canal_file << ": pool " << pool.name << " at " << flow_m3s << " m3/s: " << e.what();
    throw InputError(os.str());
  }
}

std::string NotAPoolMessage(const sim::Canal& canal, const std::string& canal_file,
                            const std::string& pool) {
  std::string names;
  for (const sim::Pool& p : canal.pools) names += (names.empty() ? "" : ", ") + p.name;
  return "--pool '" + pool + "' is not a pool of " + canal_file + " (pools: " + names + ")";
}

core::IdzTheory PoolTheory(const std::string& canal_file, const std::string& pool,
                           double flow_m3s) {
  sim::Canal canal;
  try {
    canal = sim::LoadCanal(canal_file);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  for (const sim::Pool& p : canal.pools) {
    if (p.name == pool) return TheoryOf(canal_file, p, flow_m3s);
  }
  throw InputError(NotAPoolMessage(canal, canal_file, pool));
}

}  // namespace canalid::cli
