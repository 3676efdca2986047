#pragma once

namespace canalid::core {

/// Gravity acceleration (m/s^2) used by every hydraulic formula (the simulator's and the theory's).
inline constexpr double kGravity = 9.81;

/// Geometry and Manning friction of a trapezoidal section (bottom width b, side slope m H:V)
/// at depth h (m):  A = (b + m h) h,  T = b + 2 m h,  P = b + 2 h sqrt(1 + m^2).
/// The friction term used by the momentum equation is G = A Sf = n^2 Q|Q| P^(4/3) / A^(7/3).
class TrapezoidSection final {
 public:
  /// @throws std::invalid_argument on a negative width or side slope, both zero, or n <= 0.
  TrapezoidSection(double bottom_width_m, double side_slope, double manning_n);
  double Area(double depth_m) const { return (b_ + m_ * depth_m) * depth_m; }
  double TopWidth(double depth_m) const { return b_ + 2.0 * m_ * depth_m; }
  double Perimeter(double depth_m) const { return b_ + 2.0 * depth_m * side_; }
  /// dT/dh and dP/dh, the same at every depth of a trapezoid.
  double TopWidthPerDepth() const { return 2.0 * m_; }
  double PerimeterPerDepth() const { return 2.0 * side_; }
  /// G = A Sf (m^2) and its partial derivatives with respect to depth and flow.
  void Friction(double depth_m, double flow_m3s, double* g, double* dg_dh, double* dg_dq) const;
  /// Friction slope Sf = n^2 Q|Q| / (A^2 R^(4/3)).
  double FrictionSlope(double depth_m, double flow_m3s) const;
  /// Froude number squared Q^2 T / (g A^3).
  double FroudeSquared(double depth_m, double flow_m3s) const;
  /// Normal depth: the depth whose friction slope equals `bed_slope` at `flow_m3s` (bisection to
  /// 1e-12 relative).  @throws std::invalid_argument unless flow > 0 and bed_slope > 0.
  double NormalDepth(double flow_m3s, double bed_slope) const;

 private:
  double b_;
  double m_;
  double n2_;
  double side_;
};

}  // namespace canalid::core
