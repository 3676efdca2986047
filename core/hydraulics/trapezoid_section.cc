#include "core/hydraulics/trapezoid_section.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/numerics/cube_root.h"

namespace canalid::core {

TrapezoidSection::TrapezoidSection(double bottom_width_m, double side_slope, double manning_n)
    : b_(bottom_width_m),
      m_(side_slope),
      n2_(manning_n * manning_n),
      side_(std::sqrt(1.0 + side_slope * side_slope)) {
  if (!(bottom_width_m >= 0.0) || !(side_slope >= 0.0) || bottom_width_m + side_slope <= 0.0) {
    std::ostringstream os;
    os << "TrapezoidSection: bottom_width_m " << bottom_width_m << " and side_slope " << side_slope
       << " must be >= 0 and not both 0";
    throw std::invalid_argument(os.str());
  }
  if (!(manning_n > 0.0)) {
    throw std::invalid_argument("TrapezoidSection: manning_n " + std::to_string(manning_n) +
                                " must be > 0");
  }
}

void TrapezoidSection::Friction(double depth_m, double flow_m3s, double* g, double* dg_dh,
                                double* dg_dq) const {
  const double a = Area(depth_m);
  const double p = Perimeter(depth_m);
  const double t = TopWidth(depth_m);
  const double a2 = a * a;
  // One cube root per call: P^(4/3) / A^(7/3) = cbrt(P^4 / A^7).
  const double k = n2_ * CubeRoot((p * p) * (p * p) / (a2 * a2 * a2 * a));  // G = k Q|Q|
  const double qq = flow_m3s * std::abs(flow_m3s);
  *g = k * qq;
  // d ln k / dh = 4/3 P'/P - 7/3 T/A, with P' = 2 sqrt(1 + m^2).
  const double dlnk = (4.0 / 3.0) * 2.0 * side_ / p - (7.0 / 3.0) * t / a;
  *dg_dh = *g * dlnk;
  *dg_dq = 2.0 * k * std::abs(flow_m3s);
}

double TrapezoidSection::FrictionSlope(double depth_m, double flow_m3s) const {
  double g = 0.0, dh = 0.0, dq = 0.0;
  Friction(depth_m, flow_m3s, &g, &dh, &dq);
  return g / Area(depth_m);
}

double TrapezoidSection::FroudeSquared(double depth_m, double flow_m3s) const {
  const double a = Area(depth_m);
  return flow_m3s * flow_m3s * TopWidth(depth_m) / (kGravity * a * a * a);
}

double TrapezoidSection::NormalDepth(double flow_m3s, double bed_slope) const {
  if (!(flow_m3s > 0.0) || !(bed_slope > 0.0) || !std::isfinite(flow_m3s) ||
      !std::isfinite(bed_slope)) {
    std::ostringstream os;
    os << "normal depth: flow " << flow_m3s << " m3/s and bed slope " << bed_slope
       << " must both be finite and > 0";
    throw std::invalid_argument(os.str());
  }
  // Sf decreases monotonically with depth: bracket, then bisect.
  double low = 0.0;
  double high = 1.0;
  while (FrictionSlope(high, flow_m3s) > bed_slope) {
    low = high;
    high *= 2.0;
    if (high > 1e6) throw std::invalid_argument("normal depth: no depth below 1e6 m carries it");
  }
  for (int i = 0; i < 200 && high - low > 1e-12 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (FrictionSlope(mid, flow_m3s) > bed_slope ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

}  // namespace canalid::core
