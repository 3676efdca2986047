#pragma once
#include <string>
#include <vector>

#include "core/hydraulics/trapezoid_section.h"
#include "sim/level_pid.h"

namespace canalid::sim {

/// Gravity acceleration (m/s^2) used by every hydraulic formula of the simulator: core's.
using core::kGravity;

/// The structure at the downstream end of a pool.  Levels are measured from its sill, which is the
/// bed at the downstream end of the pool it closes; `drop_m` is the bed drop from that sill to the
/// bed at the upstream end of the next pool.
///  - kUndershotGate: Q = Cd w u sign(dh) sqrt(2 g |dh|), dh = y_up - max(y_dn, u) (free flow
///    when the tailwater is below the gate lip u, submerged otherwise).  setting = opening u (m).
///  - kWeir (overshot gate): Q = Cw w H1^1.5 (1 - (H2/H1)^1.5)^0.385, H1 = y_up - crest,
///    H2 = max(y_dn - crest, 0) (Villemonte submergence).  setting = crest height above sill (m).
///  - kPump: Q = setting (m^3/s) whatever the levels; also models a held outflow.
struct Structure {
  enum class Type { kUndershotGate, kWeir, kPump };
  Type type = Type::kUndershotGate;
  double width_m = 1.0;
  double coefficient = 0.6;               ///< Cd (gate) or Cw (weir, m^0.5/s); unused by pumps.
  double setting = 0.0;                   ///< opening_m, crest_m or flow_m3s (see Type).
  bool setting_from_steady_state = true;  ///< compute setting so the initial steady state holds.
  double drop_m = 0.0;                    ///< bed drop to the next pool (m, >= 0).
  /// Tailwater level above the sill (m), only for the last pool; below 0 means free outfall.
  double tailwater_m = -1.0;
};

/// Offtake at the downstream end of a pool, just upstream of its structure.
///  - kFixedFlow: q = setting (m^3/s) while the depth exceeds `outlet_m`.
///  - kOrifice:   q = Cd * setting * sqrt(2 g (y - outlet_m)), setting = orifice area (m^2).
struct Offtake {
  enum class Type { kNone, kFixedFlow, kOrifice };
  Type type = Type::kNone;
  double setting = 0.0;
  double coefficient = 0.6;
  double outlet_m = 0.0;  ///< outlet (orifice centre) height above the pool's downstream bed (m).
};

/// One pool (reach) with a trapezoidal prismatic section and Manning friction.
struct Pool {
  std::string name;
  double length_m = 0.0;
  double bottom_width_m = 0.0;
  double side_slope = 0.0;  ///< horizontal per vertical.
  double bed_slope = 0.0;
  double manning_n = 0.0;
  double bank_depth_m = 0.0;
  double target_depth_m = 0.0;  ///< depth at the downstream end at the initial steady state.
  Structure structure;
  Offtake offtake;
};

/// Upstream boundary of the first pool: a flow hydrograph or a reservoir level (depth above the
/// bed at the upstream end of the first pool).
struct UpstreamBoundary {
  enum class Type { kFlow, kLevel };
  Type type = Type::kFlow;
  double flow_m3s = 0.0;  ///< steady inflow (kFlow) or the flow the steady state is built for.
};

/// A local level loop of the plant: a PID (LevelPid) that sets a pump's flow so as to hold the
/// depth at one end of a pool.  The pump is the upstream inflow (`actuator_pool` empty; the
/// upstream boundary must be a flow) or the pump structure of a named pool.  More flow raises
/// the held level when the pump is upstream of the level's pool (the inflow, or a pool before
/// it) and lowers it otherwise (the pool's own outflow pump or one further down); that sign is
/// derived, so the gains are all >= 0.  While the loop runs it owns its pump: a setting written
/// to that input from outside is replaced at every step.
struct LevelControl {
  std::string name;
  std::string level_pool;        ///< pool whose depth is held.
  bool level_downstream = true;  ///< depth at the pool's downstream end, else upstream end.
  std::string actuator_pool;     ///< empty: the upstream inflow; else that pool's pump.
  LevelPidConfig pid;            ///< direct_action is derived (see above).
};

/// A chain of pools.  Numerical parameters of the Preissmann scheme are part of it.
struct Canal {
  std::string name;
  std::vector<Pool> pools;
  UpstreamBoundary upstream;
  double max_dx_m = 100.0;  ///< largest space step; each pool gets ceil(L / max_dx) cells.
  double theta = 0.65;      ///< Preissmann time weighting, 0.5 < theta <= 1.
  std::vector<LevelControl> level_controls;
};

/// Index of the pool named `name`, or -1.
int FindPoolIndex(const Canal& canal, const std::string& name);

/// Throws std::invalid_argument naming the pool and the field if a value is outside its range,
/// or naming the level control whose pools do not exist or whose actuator is not a pump.
void ValidateCanal(const Canal& canal);

}  // namespace canalid::sim
