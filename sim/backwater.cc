#include "sim/backwater.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sim/hydraulics.h"

namespace canalid::sim {

std::vector<double> SteadyProfile(const Pool& pool, double flow_m3s, int num_cells,
                                  double downstream_depth_m) {
  if (!(flow_m3s >= 0.0) || !(downstream_depth_m > 0.0) || num_cells < 1) {
    std::ostringstream os;
    os << "SteadyProfile(" << pool.name << "): flow_m3s " << flow_m3s << " must be >= 0, "
       << "downstream_depth_m " << downstream_depth_m << " > 0 and num_cells " << num_cells
       << " >= 1";
    throw std::invalid_argument(os.str());
  }
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  const double dx = pool.length_m / num_cells;
  const double q = flow_m3s;
  auto froude2 = [&](double h) {
    const double area = section.Area(h);
    return q * q * section.TopWidth(h) / (kGravity * area * area * area);
  };
  if (froude2(downstream_depth_m) >= 1.0) {
    std::ostringstream os;
    os << "SteadyProfile(" << pool.name << "): downstream depth " << downstream_depth_m
       << " m is not subcritical at " << flow_m3s << " m3/s";
    throw std::runtime_error(os.str());
  }
  std::vector<double> depth(static_cast<std::size_t>(num_cells + 1));
  depth[static_cast<std::size_t>(num_cells)] = downstream_depth_m;
  for (int j = num_cells - 1; j >= 0; --j) {
    const double hr = depth[static_cast<std::size_t>(j) + 1];
    const double ar = section.Area(hr);
    double gr = 0.0, gr_h = 0.0, gr_q = 0.0;
    section.Friction(hr, q, &gr, &gr_h, &gr_q);
    const double fr = q * q / ar;
    auto residual = [&](double hl, double* derivative) {
      const double al = section.Area(hl);
      const double tl = section.TopWidth(hl);
      double gl = 0.0, gl_h = 0.0, gl_q = 0.0;
      section.Friction(hl, q, &gl, &gl_h, &gl_q);
      const double abar = 0.5 * (al + ar);
      const double slope = (hr - hl) / dx - pool.bed_slope;
      const double fl = q * q / al;
      *derivative = (q * q * tl / (al * al)) / dx + kGravity * 0.5 * tl * slope -
                    kGravity * abar / dx + 0.5 * kGravity * gl_h;
      return (fr - fl) / dx + kGravity * abar * slope + 0.5 * kGravity * (gl + gr);
    };
    // Start from the explicit step and apply damped Newton; subcritical roots lie above h_c.
    const double sf = section.FrictionSlope(hr, q);
    double h = hr - (pool.bed_slope - sf) * dx;
    if (!(h > 0.0)) h = hr;
    bool converged = false;
    for (int it = 0; it < 100; ++it) {
      double d = 0.0;
      const double r = residual(h, &d);
      double step = -r / d;
      if (!std::isfinite(step)) break;
      // Never cross half of the current depth in one step, to stay on the subcritical branch.
      if (step < -0.5 * h) step = -0.5 * h;
      h += step;
      if (std::abs(step) < 1e-13 * (1.0 + h)) {
        converged = true;
        break;
      }
    }
    if (!converged || !(h > 0.0) || froude2(h) >= 1.0) {
      std::ostringstream os;
      os << "SteadyProfile(" << pool.name << "): no subcritical profile at " << flow_m3s
         << " m3/s from downstream depth " << downstream_depth_m << " m (failed at node " << j
         << ", x = " << j * dx << " m)";
      throw std::runtime_error(os.str());
    }
    depth[static_cast<std::size_t>(j)] = h;
  }
  return depth;
}

}  // namespace canalid::sim
