#include "core/hydraulics/linearised_reach.h"

#include <Eigen/LU>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::core {

LinearisedReach Linearise(const TrapezoidSection& section, double flow_m3s, double depth_m,
                          double bed_slope, double depth_slope) {
  LinearisedReach r;
  const double a = section.Area(depth_m);
  const double t = section.TopWidth(depth_m);
  const double dt = section.TopWidthPerDepth();
  r.area_m2 = a;
  r.top_width_m = t;
  r.celerity_m_s = std::sqrt(kGravity * a / t);
  r.velocity_m_s = flow_m3s / a;
  r.froude = r.velocity_m_s / r.celerity_m_s;
  const double f2 = r.froude * r.froude;
  if (!(r.froude < 1.0)) {
    std::ostringstream os;
    os << "flow is not subcritical at depth " << depth_m << " m (Froude " << r.froude << ")";
    throw std::invalid_argument(os.str());
  }
  const double v = r.velocity_m_s;
  r.kappa =
      7.0 / 3.0 - 4.0 * a * section.PerimeterPerDepth() / (3.0 * t * section.Perimeter(depth_m));
  const double friction_slope = bed_slope - (1.0 - f2) * depth_slope;
  r.gamma_per_s = 2.0 * kGravity * friction_slope / v - 2.0 * v * t * depth_slope / a;
  r.delta_without_top_width_change =
      kGravity * t *
      ((1.0 + r.kappa) * bed_slope - (1.0 + r.kappa - f2 * (r.kappa - 2.0)) * depth_slope);
  r.delta = r.delta_without_top_width_change + v * v * dt * depth_slope;
  r.alpha_per_m =
      t / (a * r.froude * (1.0 - f2)) *
      ((2.0 + (r.kappa - 1.0) * f2) * bed_slope -
       (2.0 + (r.kappa - 1.0) * f2 - (a * dt / (t * t) + r.kappa - 2.0) * f2 * f2) * depth_slope);
  return r;
}

Eigen::Matrix2cd TransferMatrix(const LinearisedReach& r, std::complex<double> s, double length_m) {
  const double t = r.top_width_m;
  const double w = (r.celerity_m_s * r.celerity_m_s - r.velocity_m_s * r.velocity_m_s) * t;
  Eigen::Matrix2cd m;
  m << 0.0, -t * s, -(s + r.gamma_per_s) / w, (2.0 * r.velocity_m_s * t * s + r.delta) / w;
  // exp(M L) of a 2x2 matrix: e^{h L} (cosh(mu L) I + sinh(mu L)/mu (M - h I)),
  // h = trace/2, mu^2 = h^2 - det.
  const std::complex<double> h = 0.5 * m.trace();
  const std::complex<double> mu = std::sqrt(h * h - m.determinant());
  const std::complex<double> sinh_over_mu = std::abs(mu * length_m) < 1e-8
                                                ? std::complex<double>(length_m)
                                                : std::sinh(mu * length_m) / mu;
  const Eigen::Matrix2cd shifted = m - h * Eigen::Matrix2cd::Identity();
  return std::exp(h * length_m) *
         (std::cosh(mu * length_m) * Eigen::Matrix2cd::Identity() + sinh_over_mu * shifted);
}

}  // namespace canalid::core
