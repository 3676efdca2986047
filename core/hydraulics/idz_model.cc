#include "core/hydraulics/idz_model.h"

#include <cmath>

namespace canalid::core {

std::complex<double> IdzDownstreamFromInflow(const IdzModel& model, double omega_rad_s) {
  const std::complex<double> s(0.0, omega_rad_s);
  return (1.0 / (model.area_m2 * s) + model.p21_s_per_m2) * std::exp(-model.delay_s * s);
}

double IdzDownstreamFromInflowPhase(const IdzModel& model, double omega_rad_s) {
  const std::complex<double> s(0.0, omega_rad_s);
  return std::arg(1.0 / (model.area_m2 * s) + model.p21_s_per_m2) - omega_rad_s * model.delay_s;
}

std::complex<double> IdzDownstreamFromOutflow(const IdzModel& model, double omega_rad_s) {
  const std::complex<double> s(0.0, omega_rad_s);
  return -(1.0 / (model.area_m2 * s) + model.p22_s_per_m2);
}

}  // namespace canalid::core
