// The IDZ theory approximates each pool's steady profile by a uniform part and a linear backwater
// part. Checked here against the simulator's own gradually varied profile (standard step method):
// the delay must be the travel time of a downstream wave, the integral of dx/(C + V) along the
// true profile.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/hydraulics/idz_theory.h"
#include "sim/backwater.h"
#include "sim/canal_config.h"
#include "sim/hydraulics.h"

namespace canalid::sim {
namespace {

double WaveTravelTime(const Pool& pool, double flow, int cells) {
  const std::vector<double> depth = SteadyProfile(pool, flow, cells, pool.target_depth_m);
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  auto slowness = [&](double h) {
    const double a = section.Area(h);
    return 1.0 / (std::sqrt(kGravity * a / section.TopWidth(h)) + flow / a);
  };
  const double dx = pool.length_m / cells;
  double time = 0.0;
  for (int i = 0; i < cells; ++i) {
    time += 0.5 * dx *
            (slowness(depth[static_cast<std::size_t>(i)]) +
             slowness(depth[static_cast<std::size_t>(i + 1)]));
  }
  return time;
}

TEST(IdzTheoryProfile, DelayIsTheWaveTravelTimeOnTheSimulatorsProfile) {
  for (const char* file : {"/config/sim/asce-canal1.toml", "/config/sim/asce-canal2.toml"}) {
    const Canal canal = LoadCanal(std::string(CANALID_SOURCE_DIR) + file);
    const std::vector<double> flows = SteadyPoolFlows(canal);
    for (std::size_t i = 0; i < canal.pools.size(); ++i) {
      const Pool& pool = canal.pools[i];
      const core::PoolGeometry geometry{pool.length_m,  pool.bottom_width_m, pool.side_slope,
                                        pool.bed_slope, pool.manning_n,      pool.target_depth_m};
      const double delay = core::IdzFromGeometry(geometry, flows[i]).model.delay_s;
      const double travel = WaveTravelTime(pool, flows[i], 2000);
      EXPECT_NEAR(delay / travel, 1.0, 0.01) << file << " pool " << pool.name << ": IDZ delay "
                                             << delay << " s, travel time " << travel << " s";
    }
  }
}

}  // namespace
}  // namespace canalid::sim
