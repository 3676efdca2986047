#pragma once
#include <vector>

#include "sim/canal.h"

namespace canalid::sim {

/// Steady gradually varied flow profile of one pool by the standard step method on a uniform grid
/// of `num_cells` cells, integrating upstream from `downstream_depth_m` at the downstream end.
/// Each step solves, for the upstream depth h_j given h_{j+1} (Newton on a scalar equation),
///   (F_{j+1} - F_j)/dx + g Abar ((h_{j+1} - h_j)/dx - S0) + g (G_j + G_{j+1})/2 = 0,
/// with F = Q^2/A, Abar = (A_j + A_{j+1})/2 and G = A Sf: the trapezoidal discretisation of
/// dy/dx = (S0 - Sf)/(1 - Fr^2), which is also the exact steady state of the Preissmann scheme
/// used by SaintVenantCanal (so a simulation started from it stays still).
/// Returns num_cells + 1 depths (m) from the upstream end to the downstream end.
/// @throws std::invalid_argument on non-positive flow, depth or cells, or std::runtime_error if
/// the profile cannot be continued (flow at or beyond critical, or the pool runs dry).
std::vector<double> SteadyProfile(const Pool& pool, double flow_m3s, int num_cells,
                                  double downstream_depth_m);

}  // namespace canalid::sim
