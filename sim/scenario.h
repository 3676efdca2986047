#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/canal.h"
#include "sim/sensor_model.h"

namespace canalid::sim {

/// A plant input that events act on: the upstream boundary, a structure setting or an offtake.
struct InputRef {
  enum class Kind { kUpstream, kStructure, kOfftake };
  Kind kind = Kind::kUpstream;
  int pool = 0;  ///< index into Scenario::canal.pools
};

/// A timed change of an input.  kSet: value from time_s on; kStep: value added from time_s on;
/// kPrbs: amplitude * PRBS(order, seed) with the given clock added on [time_s, end_s).
struct Event {
  enum class Kind { kSet, kStep, kPrbs };
  Kind kind = Kind::kStep;
  InputRef input;
  double time_s = 0.0;
  double value = 0.0;
  double amplitude = 0.0;
  double clock_s = 0.0;
  int order = 7;
  std::uint64_t seed = 1;
  double end_s = 0.0;
};

/// A plant output read for a CSV column.
struct OutputRef {
  enum class Kind {
    kInflow,
    kOutflow,
    kLevelUpstream,
    kLevelDownstream,
    kVolume,
    kStructureFlow,
    kStructureSetting,
    kOfftakeFlow
  };
  Kind kind = Kind::kInflow;
  int pool = 0;
};

struct OutputColumn {
  std::string name;
  std::string variable;  ///< as written in the file, e.g. "pool2.inflow"
  OutputRef ref;
  SensorConfig sensor;
};

/// A headless simulation run (format: docs/canalsim.md).  `canal` is the canal file restricted to
/// the simulated pools with the scenario's overrides applied.
struct Scenario {
  Canal canal;
  double duration_s = 0.0;
  double output_period_s = 0.0;
  double time_step_s = 0.0;
  std::uint64_t seed = 1;
  std::vector<Event> events;
  std::vector<OutputColumn> columns;
};

/// Loads a scenario for the given canal.  @throws ConfigError listing every problem with
/// file:line:column.
Scenario LoadScenario(const std::string& path, const Canal& canal);
/// Parses `text` as LoadScenario parses a file's contents; messages name the file `name`.
/// @throws ConfigError listing every problem with name:line:column.
Scenario ParseScenario(std::string_view text, const std::string& name, const Canal& canal);

}  // namespace canalid::sim
