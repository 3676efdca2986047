#include "core/hydraulics/idz_theory.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/hydraulics/linearised_reach.h"
#include "core/hydraulics/trapezoid_section.h"

namespace canalid::core {
namespace {

// One part of the pool with constant coefficients (uniform, or the linear backwater part).
struct PartModel {
  double tau_d = 0.0;
  double tau_u = 0.0;
  double ad = 0.0;
  double au = 0.0;
  double p11 = 0.0;
  double p12 = 0.0;
  double p21 = 0.0;
  double p22 = 0.0;
};

// log(1 + e^z) without overflow.
double Softplus(double z) { return std::max(z, 0.0) + std::log1p(std::exp(-std::abs(z))); }

// e^z / (1 + e^z) without overflow.
double Logistic(double z) {
  return z >= 0.0 ? 1.0 / (1.0 + std::exp(-z)) : std::exp(z) / (1.0 + std::exp(z));
}

PartModel Part(const LinearisedReach& r, double length) {
  PartModel part;
  if (length <= 0.0) return part;
  const double t = r.top_width_m;
  const double c = r.celerity_m_s;
  const double v = r.velocity_m_s;
  const double f = r.froude;
  const double w = t * (c * c - v * v);
  part.tau_d = length / (c + v);
  part.tau_u = length / (c - v);
  const double delta = r.delta_without_top_width_change;
  const double z = delta * length / w;
  if (std::abs(z) < 1e-12) {
    part.ad = part.au = t * length;
  } else {
    part.ad = -t * w / delta * std::expm1(-z);
    part.au = t * w / delta * std::expm1(z);
  }
  const double ax = r.alpha_per_m * length;
  const double share = Logistic(ax);  // e^{ax} / (1 + e^{ax})
  const double up = (1.0 - f) / (1.0 + f);
  part.p11 = 1.0 / (t * c * (1.0 - f)) * std::sqrt(1.0 - share + up * up * share);
  part.p22 = 1.0 / (t * c * (1.0 + f)) * std::sqrt(1.0 - share + share / (up * up));
  const double half_softplus = 0.5 * Softplus(ax);
  const double cross = 2.0 / (t * c * (1.0 - f * f));
  const double decay = r.delta * length / (2.0 * w);
  part.p12 = cross * std::exp(-decay - half_softplus);
  part.p21 = cross * std::exp(decay - half_softplus);
  return part;
}

// p22(s) = y(L)/q(L) with q(0) = 0 over the parts in series (upstream part first).
double OutflowResponse(const LinearisedReach& up, double up_length, const LinearisedReach& down,
                       double down_length, double s) {
  Eigen::Matrix2cd phi = TransferMatrix(down, s, down_length);
  if (up_length > 0.0) phi = phi * TransferMatrix(up, s, up_length);
  return (phi(1, 1) / phi(0, 1)).real();
}

// k of response(s) = k(0)/s + k(1) + k(2) s + O(s^2) at low frequencies, from three real
// frequencies far below 1/delay (solved exactly).
template <typename Response>
Eigen::Vector3d LowFrequencyExpansion(const Response& response, double delay_s) {
  const double e = 1e-4 / delay_s;
  Eigen::Matrix3d x;
  Eigen::Vector3d p;
  for (int i = 0; i < 3; ++i) {
    const double s = e * (i + 1);
    x.row(i) << 1.0 / s, 1.0, s;
    p(i) = response(s);
  }
  return x.partialPivLu().solve(p);
}

// trace(M(s)) of TransferMatrix: (2 V T s + delta)/W.
double TransferTrace(const LinearisedReach& r, double s) {
  const double w =
      (r.celerity_m_s * r.celerity_m_s - r.velocity_m_s * r.velocity_m_s) * r.top_width_m;
  return (2.0 * r.velocity_m_s * r.top_width_m * s + r.delta) / w;
}

// p21(s) = y(L)/q(0) with q(L) = 0 over the parts in series (upstream part first).
double InflowResponse(const LinearisedReach& up, double up_length, const LinearisedReach& down,
                      double down_length, double s) {
  Eigen::Matrix2cd phi = TransferMatrix(down, s, down_length);
  // det exp(M L) = exp(trace(M) L), exactly: the product of the entries would cancel.
  double log_det = TransferTrace(down, s) * down_length;
  if (up_length > 0.0) {
    phi = phi * TransferMatrix(up, s, up_length);
    log_det += TransferTrace(up, s) * up_length;
  }
  return (-std::exp(log_det) / phi(0, 1)).real();
}

void CheckPositive(const char* name, double value) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    std::ostringstream os;
    os << name << " " << value << " must be a finite number > 0";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

IdzTheory IdzFromGeometry(const PoolGeometry& pool, double flow_m3s) {
  CheckPositive("length_m", pool.length_m);
  CheckPositive("downstream depth", pool.downstream_depth_m);
  CheckPositive("flow", flow_m3s);
  CheckPositive("manning_n", pool.manning_n);
  if (!std::isfinite(pool.bed_slope)) throw std::invalid_argument("bed_slope must be finite");
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  const double y_l = pool.downstream_depth_m;
  const double f2_l = section.FroudeSquared(y_l, flow_m3s);
  if (!(f2_l < 1.0)) {
    std::ostringstream os;
    os << "flow " << flow_m3s << " m3/s is not subcritical at the downstream depth " << y_l
       << " m (Froude " << std::sqrt(f2_l) << ")";
    throw std::invalid_argument(os.str());
  }
  IdzTheory theory;
  theory.depth_slope = (pool.bed_slope - section.FrictionSlope(y_l, flow_m3s)) / (1.0 - f2_l);
  const double length = pool.length_m;
  double uniform = 0.0;
  if (pool.bed_slope > 0.0) {
    theory.normal_depth_m = section.NormalDepth(flow_m3s, pool.bed_slope);
    if (theory.depth_slope != 0.0) {
      uniform = std::max(0.0, length - (y_l - theory.normal_depth_m) / theory.depth_slope);
    } else {
      uniform = length;
    }
  }
  theory.uniform_length_m = uniform;
  const double backwater = length - uniform;
  theory.upstream_depth_m =
      uniform > 0.0 ? theory.normal_depth_m : y_l - theory.depth_slope * length;
  const double mid_depth = y_l - 0.5 * backwater * theory.depth_slope;
  const LinearisedReach down_reach =
      Linearise(section, flow_m3s, mid_depth, pool.bed_slope, theory.depth_slope);
  const LinearisedReach up_reach =
      uniform > 0.0 ? Linearise(section, flow_m3s, theory.normal_depth_m, pool.bed_slope, 0.0)
                    : down_reach;
  const PartModel down = Part(down_reach, backwater);
  IdzModel& m = theory.model;
  const PartModel up = Part(up_reach, uniform);
  if (uniform <= 0.0 || backwater <= 0.0) {
    const PartModel& only = uniform <= 0.0 ? down : up;
    m = IdzModel{only.tau_d, only.ad, only.p21, only.p22, only.tau_u, only.au, only.p11, only.p12};
  } else {
    // The parts share the level and the flow where they meet (see the header).
    const double coupling = down.p11 + up.p22;
    m.delay_s = up.tau_d + down.tau_d;
    m.upstream_delay_s = up.tau_u + down.tau_u;
    m.area_m2 = down.ad * (1.0 + up.ad / down.au);
    m.upstream_area_m2 = up.au * (1.0 + down.au / up.ad);
    m.p11_s_per_m2 = up.p11 + up.p12 * up.p21 / coupling;
    m.p12_s_per_m2 = up.p12 * down.p12 / coupling;
    m.p21_s_per_m2 = up.p21 * down.p21 / coupling;
    m.p22_s_per_m2 = down.p22 + down.p12 * down.p21 / coupling;
  }
  // One part (the pool's only one) or the two in series.
  const bool two_parts = uniform > 0.0 && backwater > 0.0;
  const double up_length = two_parts ? uniform : 0.0;
  const LinearisedReach& last = backwater > 0.0 ? down_reach : up_reach;
  const double last_length = backwater > 0.0 ? backwater : uniform;
  // p22(s) = -1/(A s) - c + O(s): the constant c.
  theory.outflow_gain_low_frequency_s_per_m2 = -LowFrequencyExpansion(
      [&](double s) { return OutflowResponse(up_reach, up_length, last, last_length, s); },
      m.delay_s)(1);
  // p21(s) = 1/(A s) - tau/A + O(s): tau.
  const Eigen::Vector3d inflow = LowFrequencyExpansion(
      [&](double s) { return InflowResponse(up_reach, up_length, last, last_length, s); },
      m.delay_s);
  theory.delay_low_frequency_s = -inflow(1) / inflow(0);
  return theory;
}

}  // namespace canalid::core
