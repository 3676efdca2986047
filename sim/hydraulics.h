#pragma once
#include <vector>

#include "core/hydraulics/trapezoid_section.h"
#include "sim/canal.h"

namespace canalid::sim {

/// The section geometry and friction of core, used by the simulator unqualified.
using core::TrapezoidSection;

/// Flow through a structure (m^3/s, positive downstream) for levels measured above its sill:
/// `upstream_m` on the pool side and `downstream_m` on the other side (see Structure for the
/// formulas), with the given setting.  A tiny head (below 1e-4 m) is regularised so that the flow
/// has a finite derivative at zero head.
double StructureFlow(const Structure& structure, double setting, double upstream_m,
                     double downstream_m);

/// Offtake flow (m^3/s) at depth `depth_m` above the pool's downstream bed.
double OfftakeFlow(const Offtake& offtake, double setting, double depth_m);

/// The flow of each pool at the canal's initial steady state: the upstream flow, less the
/// offtakes of the pools before it at their settings and target depths.
/// @throws std::invalid_argument naming the pool whose offtakes take more than the inflow.
std::vector<double> SteadyPoolFlows(const Canal& canal);

/// The structure setting that passes `flow_m3s` at the given levels (bisection on the monotone
/// formula).  @throws std::invalid_argument if no setting in the physical range passes that flow
/// (for example a gate whose upstream level is below the downstream one).
double SteadyStructureSetting(const Structure& structure, double flow_m3s, double upstream_m,
                              double downstream_m);

}  // namespace canalid::sim
