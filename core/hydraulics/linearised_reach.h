#pragma once
#include <Eigen/Core>
#include <complex>

#include "core/hydraulics/trapezoid_section.h"

namespace canalid::core {

/// The Saint-Venant equations of a trapezoidal channel linearised about a steady flow Q at one
/// depth Y, for the deviations of flow q (m^3/s) and depth y (m):
///   T y_t + q_x = 0,
///   q_t + 2 V q_x + (C^2 - V^2) T y_x + gamma q - delta y = 0,
/// where the steady depth changes along the channel at the rate Y' = dY/dx (0 in uniform flow),
/// Sf = S0 - (1 - F^2) Y' is the friction slope that goes with it, and (Manning friction,
/// kappa = 7/3 - 4 A P'/(3 T P)):
///   gamma = 2 g Sf / V - 2 V T Y' / A,
///   delta = g T ((1 + kappa) S0 - (1 + kappa - F^2 (kappa - 2)) Y') + V^2 T' Y'.
struct LinearisedReach {
  double area_m2 = 0.0;
  double top_width_m = 0.0;
  double celerity_m_s = 0.0;  ///< C = sqrt(g A / T)
  double velocity_m_s = 0.0;  ///< V = Q / A
  double froude = 0.0;        ///< V / C
  double kappa = 0.0;
  double gamma_per_s = 0.0;
  double delta = 0.0;  ///< m^2/s^2 (delta y has the units of q_t)
  /// delta without the top width's change V^2 T' Y' (Litrico & Fromion's areas use it).
  double delta_without_top_width_change = 0.0;
  /// a of the high-frequency gains (1/m): T/(A F (1 - F^2)) ((2 + (kappa - 1) F^2) S0 -
  /// (2 + (kappa - 1) F^2 - (A T'/T^2 + kappa - 2) F^4) Y').
  double alpha_per_m = 0.0;
};

/// @throws std::invalid_argument if the flow is not subcritical at that depth.
LinearisedReach Linearise(const TrapezoidSection& section, double flow_m3s, double depth_m,
                          double bed_slope, double depth_slope);

/// The transfer matrix of [q; y] over `length_m` of a channel with these constant coefficients,
/// in the Laplace domain: [q(x + L); y(x + L)] = exp(M(s) L) [q(x); y(x)], with
///   M(s) = [[0, -T s], [-(s + gamma)/W, (2 V T s + delta)/W]],  W = (C^2 - V^2) T.
Eigen::Matrix2cd TransferMatrix(const LinearisedReach& reach, std::complex<double> s,
                                double length_m);

}  // namespace canalid::core
