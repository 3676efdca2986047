#pragma once
#include "core/hydraulics/idz_model.h"

namespace canalid::core {

/// A prismatic trapezoidal pool and its downstream condition.
struct PoolGeometry {
  double length_m = 0.0;
  double bottom_width_m = 0.0;
  double side_slope = 0.0;  ///< horizontal per vertical
  double bed_slope = 0.0;   ///< m/m, positive downhill; 0 or negative: the whole pool is backwater
  double manning_n = 0.0;   ///< s/m^(1/3)
  double downstream_depth_m = 0.0;
};

/// The IDZ model the geometry gives, with the steady profile it was computed on.
struct IdzTheory {
  IdzModel model;
  /// Normal depth at this flow (m); 0 when the bed is not sloping downhill (no uniform flow).
  double normal_depth_m = 0.0;
  /// Length of the upstream part in uniform flow (m); 0 when the whole pool is backwater.
  double uniform_length_m = 0.0;
  /// Depth at the upstream end of the approximated profile (m).
  double upstream_depth_m = 0.0;
  /// Slope of the water depth along the backwater part, dY/dx at the downstream end (m/m).
  double depth_slope = 0.0;
  /// The outflow's direct gain at low frequencies (s/m^2): the constant c of
  /// p22(s) = -(1/(A s) + c + O(s)) as s -> 0, from the linearised equations (LinearisedReach)
  /// over the same two parts.  It differs from the high-frequency p22 of the model (ASCE canal 2
  /// pool 2 at 10 m3/s: 0.0133 against 0.0216) and is the one that a level-driven outflow, slow
  /// beside the delay, couples into the level: the prior of closed-loop identification.
  double outflow_gain_low_frequency_s_per_m2 = 0.0;
  /// The inflow's delay at low frequencies (s): tau of p21(s) = 1/(A s) - tau/A + O(s) as s -> 0
  /// (outflow held), from the linearised equations over the same two parts.  It is where the
  /// integrator's ramp starts, the delay a record shows when the wave front (p21) is too small to
  /// see: on a diffusive pool it is later than the front's arrival, the model's delay (ASCE canal 1
  /// pools 5-8: 1.38-1.40 x), and on a backwater pool with a large front earlier (canal 2 pool 2:
  /// 115 s against 682 s, the front p21 carrying the early response).
  double delay_low_frequency_s = 0.0;
};

/// The IDZ model of a pool at a steady flow, by the analytical approximation of the Saint-Venant
/// equations linearised about the steady profile (Litrico & Fromion 2004, J. Irrig. Drain. Eng.
/// 130(5)), computed as follows:
///  - the profile is a uniform part at the normal depth followed by a backwater part whose depth
///    varies linearly with the slope dY/dx = (S0 - Sf)/(1 - F^2) of the downstream end, so the
///    uniform part has length max(0, L - (Y_L - Y_n)/(dY/dx));
///  - each part has constant coefficients, taken at the normal depth for the uniform part and at
///    the depth of the middle of the backwater part: celerity C, velocity V, Froude F, top width T
///    and, with kappa = 7/3 - 4 A P'/(3 T P),
///      delta = g T ((1 + kappa) S0 - (1 + kappa - F^2 (kappa - 2)) dY/dx),
///    the coefficient of the level in the linearised momentum equation;
///  - a part of length x gets  tau_d = x/(C + V),  tau_u = x/(C - V),
///      Ad = T W/delta (1 - e^{-delta x/W}),  Au = T W/delta (e^{delta x/W} - 1),  W = T (C^2 -
///      V^2)
///    from the low frequencies, and the high-frequency gains
///      p21 = 2/(T C (1 - F^2)) e^{delta' x/(2W)} / sqrt(1 + e^{a x}),
///      p22 = 1/(T C (1 + F)) sqrt((1 + ((1 + F)/(1 - F))^2 e^{a x}) / (1 + e^{a x})),
///    (p12 and p11 likewise), where a = T/(A F (1 - F^2)) ((2 + (kappa - 1) F^2) S0 -
///    (2 + (kappa - 1) F^2 - (A T'/T^2 + kappa - 2) F^4) dY/dx) and delta' = delta + V^2 T' dY/dx
///    adds the top width's change along the backwater part (T' = dT/dY);
///  - the two parts in series share the level and the flow where they meet, which gives
///      tau_d = tau_d1 + tau_d2,   Ad = Ad2 (1 + Ad1/Au2),
///      p21 = p21_1 p21_2 / (p11_2 + p22_1),   p22 = p22_2 + p12_2 p21_2 / (p11_2 + p22_1).
/// The areas use delta and the high-frequency gains delta'; with the other choice the published
/// table (tests/data/reference/asce_idz_litrico_fromion_2004.csv) is missed by 5.7 % (area) or
/// 5.1 % (p21), with this one it is met to 0.12 % (delay), 0.02 % (area), 1.5 % (p21, the
/// table's rounding of values near 1e-5) and 0.2 % (p22) on all 32 rows.
/// The approximated profile never runs dry: a backwater part that would reach the bed is cut at
/// the normal depth instead.  @throws std::invalid_argument naming the value on a non-finite or
/// non-positive length, flow, depth or roughness, a bad section, or a supercritical flow.
IdzTheory IdzFromGeometry(const PoolGeometry& pool, double flow_m3s);

}  // namespace canalid::core
