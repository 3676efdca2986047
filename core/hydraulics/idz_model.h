#pragma once
#include <complex>

namespace canalid::core {

/// The integrator-delay-zero (IDZ) model of a canal pool (Litrico & Fromion 2004), levels (m) at
/// both ends as responses to the flows (m^3/s) at both ends, in the Laplace domain:
///   y(0, s) = p11(s) q(0, s) + p12(s) q(L, s),   y(L, s) = p21(s) q(0, s) + p22(s) q(L, s),
///   p11(s) =  1/(Au s) + p11,        p12(s) = -(1/(Au s) + p12) e^{-tau_u s},
///   p21(s) = (1/(Ad s) + p21) e^{-tau_d s},  p22(s) = -(1/(Ad s) + p22).
/// Ad is the backwater area and tau_d the delay of the downstream level that canal control uses;
/// p21 and p22 are the direct (high-frequency) gains of the inflow and of the outflow.
struct IdzModel {
  double delay_s = 0.0;           ///< tau_d
  double area_m2 = 0.0;           ///< Ad
  double p21_s_per_m2 = 0.0;      ///< inflow's direct gain on the downstream level
  double p22_s_per_m2 = 0.0;      ///< outflow's direct gain on the downstream level
  double upstream_delay_s = 0.0;  ///< tau_u
  double upstream_area_m2 = 0.0;  ///< Au
  double p11_s_per_m2 = 0.0;
  double p12_s_per_m2 = 0.0;
};

/// p21(j omega): the downstream level's response to the inflow.
std::complex<double> IdzDownstreamFromInflow(const IdzModel& model, double omega_rad_s);
/// The phase (rad) of p21(j omega) as a continuous function of omega: the zero's phase, in
/// (-pi/2, 0), less the delay's omega tau_d (no unwrapping of a sampled curve needed).
double IdzDownstreamFromInflowPhase(const IdzModel& model, double omega_rad_s);
/// p22(j omega): the downstream level's response to the outflow.
std::complex<double> IdzDownstreamFromOutflow(const IdzModel& model, double omega_rad_s);

}  // namespace canalid::core
