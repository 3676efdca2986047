#pragma once
#include <cstdint>
#include <functional>
#include <ostream>

#include "sim/saint_venant.h"
#include "sim/scenario.h"

namespace canalid::sim {

struct RunSummary {
  double simulated_s = 0.0;
  long steps = 0;
  int rows = 0;
  MassBalance mass;
};

/// Value of an input at time t_s: its initial value, then the scenario's set/step events with
/// time_s <= t_s in file order, plus every PRBS active at t_s.  `prbs` holds one sequence per
/// event (empty for non-PRBS events).
double InputValue(const Scenario& scenario, const std::vector<std::vector<int>>& prbs,
                  const InputRef& input, double initial, double t_s);

/// Runs the scenario from its steady state and writes the CSV (header `time_s` then the output
/// columns; one row at t = 0 and every output period up to the duration, values with 12
/// significant digits, a missing reading as `nan`).  Sensor models are seeded from `seed` and the
/// column index.  `progress(t_s)` is called after each output row when given.
/// @throws std::runtime_error if the solver fails, std::invalid_argument on an infeasible steady
/// state (see SaintVenantCanal).
RunSummary RunScenario(const Scenario& scenario, std::uint64_t seed, std::ostream& csv,
                       const std::function<void(double)>& progress = {});

}  // namespace canalid::sim
