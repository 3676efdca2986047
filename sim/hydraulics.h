#pragma once
#include "sim/canal.h"

namespace canalid::sim {

/// Geometry and Manning friction of a trapezoidal section (bottom width b, side slope m H:V)
/// at depth h (m):  A = (b + m h) h,  T = b + 2 m h,  P = b + 2 h sqrt(1 + m^2).
/// The friction term used by the momentum equation is G = A Sf = n^2 Q|Q| P^(4/3) / A^(7/3).
class TrapezoidSection final {
 public:
  TrapezoidSection(double bottom_width_m, double side_slope, double manning_n);
  double Area(double depth_m) const { return (b_ + m_ * depth_m) * depth_m; }
  double TopWidth(double depth_m) const { return b_ + 2.0 * m_ * depth_m; }
  double Perimeter(double depth_m) const { return b_ + 2.0 * depth_m * side_; }
  /// G = A Sf (m^2) and its partial derivatives with respect to depth and flow.
  void Friction(double depth_m, double flow_m3s, double* g, double* dg_dh, double* dg_dq) const;
  /// Friction slope Sf = n^2 Q|Q| / (A^2 R^(4/3)).
  double FrictionSlope(double depth_m, double flow_m3s) const;

 private:
  double b_;
  double m_;
  double n2_;
  double side_;
};

/// Flow through a structure (m^3/s, positive downstream) for levels measured above its sill:
/// `upstream_m` on the pool side and `downstream_m` on the other side (see Structure for the
/// formulas), with the given setting.  A tiny head (below 1e-4 m) is regularised so that the flow
/// has a finite derivative at zero head.
double StructureFlow(const Structure& structure, double setting, double upstream_m,
                     double downstream_m);

/// Offtake flow (m^3/s) at depth `depth_m` above the pool's downstream bed.
double OfftakeFlow(const Offtake& offtake, double setting, double depth_m);

/// The structure setting that passes `flow_m3s` at the given levels (bisection on the monotone
/// formula).  @throws std::invalid_argument if no setting in the physical range passes that flow
/// (for example a gate whose upstream level is below the downstream one).
double SteadyStructureSetting(const Structure& structure, double flow_m3s, double upstream_m,
                              double downstream_m);

}  // namespace canalid::sim
