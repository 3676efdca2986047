#include "sim/scenario_runner.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/numerics/splitmix64.h"
#include "core/signal/prbs.h"

namespace canalid::sim {
namespace {

bool Same(const InputRef& a, const InputRef& b) {
  return a.kind == b.kind && (a.kind == InputRef::Kind::kUpstream || a.pool == b.pool);
}

double ReadOutput(const SaintVenantCanal& plant, const OutputRef& ref) {
  using K = OutputRef::Kind;
  switch (ref.kind) {
    case K::kInflow:
      return plant.PoolInflow(ref.pool);
    case K::kOutflow:
      return plant.PoolOutflow(ref.pool);
    case K::kLevelUpstream:
      return plant.UpstreamDepth(ref.pool);
    case K::kLevelDownstream:
      return plant.DownstreamDepth(ref.pool);
    case K::kVolume:
      return plant.PoolVolume(ref.pool);
    case K::kStructureFlow:
      return plant.StructureFlow(ref.pool);
    case K::kStructureSetting:
      return plant.structure_setting(ref.pool);
    case K::kOfftakeFlow:
      return plant.OfftakeFlow(ref.pool);
  }
  return 0.0;
}

double InitialValue(const SaintVenantCanal& plant, const InputRef& input) {
  switch (input.kind) {
    case InputRef::Kind::kUpstream:
      return plant.upstream();
    case InputRef::Kind::kStructure:
      return plant.structure_setting(input.pool);
    case InputRef::Kind::kOfftake:
      return plant.offtake_setting(input.pool);
  }
  return 0.0;
}

void Apply(SaintVenantCanal* plant, const InputRef& input, double value) {
  switch (input.kind) {
    case InputRef::Kind::kUpstream:
      plant->SetUpstream(value);
      break;
    case InputRef::Kind::kStructure:
      plant->SetStructureSetting(input.pool, value);
      break;
    case InputRef::Kind::kOfftake:
      plant->SetOfftakeSetting(input.pool, value);
      break;
  }
}

// One period of the event's m-sequence (core/signal/prbs.h, the daemon's experiments' generator):
// the scenario's seed, any value, picks the nonzero start state seed mod (2^n - 1) + 1.
std::vector<int> OnePeriod(int order, std::uint64_t seed) {
  const std::uint64_t states = (std::uint64_t{1} << order) - 1;
  core::MaximalLengthSequence sequence(order, static_cast<std::uint32_t>(seed % states + 1));
  std::vector<int> period(static_cast<std::size_t>(sequence.period()));
  for (int& value : period) value = sequence.Next();
  return period;
}

}  // namespace

double InputValue(const Scenario& scenario, const std::vector<std::vector<int>>& prbs,
                  const InputRef& input, double initial, double t_s) {
  // Event times are compared with a tolerance so that an event at 3600 s fires at the step that
  // ends at 3600 s despite rounding in t = k dt.
  const double eps = 1e-9 * (1.0 + std::abs(t_s));
  double value = initial;
  double offset = 0.0;
  for (std::size_t k = 0; k < scenario.events.size(); ++k) {
    const Event& e = scenario.events[k];
    if (!Same(e.input, input) || t_s + eps < e.time_s) continue;
    switch (e.kind) {
      case Event::Kind::kSet:
        value = e.value;
        break;
      case Event::Kind::kStep:
        value += e.value;
        break;
      case Event::Kind::kPrbs:
        if (t_s + eps < e.end_s) {
          const auto clock =
              static_cast<std::size_t>(std::floor((t_s - e.time_s + eps) / e.clock_s));
          offset += e.amplitude * prbs[k][clock % prbs[k].size()];
        }
        break;
    }
  }
  return value + offset;
}

RunSummary RunScenario(const Scenario& scenario, std::uint64_t seed, std::ostream& csv,
                       const std::function<void(double)>& progress) {
  SaintVenantCanal plant(scenario.canal);
  std::vector<std::vector<int>> prbs(scenario.events.size());
  for (std::size_t k = 0; k < scenario.events.size(); ++k) {
    const Event& e = scenario.events[k];
    if (e.kind == Event::Kind::kPrbs) prbs[k] = OnePeriod(e.order, e.seed);
  }
  // Every input an event touches, with its initial (steady-state) value.
  std::vector<std::pair<InputRef, double>> inputs;
  for (const Event& e : scenario.events) {
    bool known = false;
    for (const auto& [ref, initial] : inputs) known = known || Same(ref, e.input);
    if (!known) inputs.emplace_back(e.input, InitialValue(plant, e.input));
  }
  std::vector<SensorModel> sensors;
  for (std::size_t c = 0; c < scenario.columns.size(); ++c) {
    // Independent-looking noise streams from (seed, column).
    sensors.emplace_back(scenario.columns[c].sensor, core::SplitMix64Hash(seed * 1000003ull + c));
  }

  csv << "time_s";
  for (const OutputColumn& c : scenario.columns) csv << ',' << c.name;
  csv << '\n';
  RunSummary summary;
  const double dt = scenario.time_step_s;
  const long steps_per_row = std::lround(scenario.output_period_s / dt);
  const long rows =
      static_cast<long>(std::floor(scenario.duration_s / scenario.output_period_s + 1e-9));
  char buffer[64];
  auto write_row = [&](double t_s) {
    std::snprintf(buffer, sizeof buffer, "%.10g", t_s);
    csv << buffer;
    for (std::size_t c = 0; c < scenario.columns.size(); ++c) {
      const double v = sensors[c].Read(ReadOutput(plant, scenario.columns[c].ref), t_s,
                                       scenario.output_period_s);
      if (std::isnan(v)) {
        csv << ",nan";
      } else {
        std::snprintf(buffer, sizeof buffer, ",%.12g", v);
        csv << buffer;
      }
    }
    csv << '\n';
    ++summary.rows;
    if (progress) progress(t_s);
  };
  write_row(0.0);
  long step = 0;
  for (long row = 1; row <= rows; ++row) {
    for (long s = 0; s < steps_per_row; ++s) {
      ++step;
      const double t_new = static_cast<double>(step) * dt;
      for (const auto& [ref, initial] : inputs) {
        Apply(&plant, ref, InputValue(scenario, prbs, ref, initial, t_new));
      }
      plant.Step(dt);
    }
    write_row(static_cast<double>(step) * dt);
  }
  summary.simulated_s = static_cast<double>(step) * dt;
  summary.steps = step;
  summary.mass = plant.mass_balance();
  return summary;
}

}  // namespace canalid::sim
