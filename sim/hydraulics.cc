#include "sim/hydraulics.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::sim {
namespace {

// Below this head the square root is replaced by a linear law so that Newton sees a finite slope.
constexpr double kSmallHead = 1e-4;

double SignedRootHead(double head_m) {
  const double a = std::abs(head_m);
  const double root = a > kSmallHead ? std::sqrt(a) : a / std::sqrt(kSmallHead);
  return head_m >= 0.0 ? root : -root;
}

double WeirOneWay(double coefficient, double width_m, double crest_m, double high_m, double low_m) {
  const double h1 = high_m - crest_m;
  if (h1 <= 0.0) return 0.0;
  const double free = coefficient * width_m * h1 * std::sqrt(h1);
  const double h2 = low_m - crest_m;
  if (h2 <= 0.0) return free;
  const double ratio = std::min(h2 / h1, 1.0);
  return free * std::pow(1.0 - ratio * std::sqrt(ratio), 0.385);
}

}  // namespace

double StructureFlow(const Structure& s, double setting, double upstream_m, double downstream_m) {
  switch (s.type) {
    case Structure::Type::kPump:
      return setting;
    case Structure::Type::kUndershotGate: {
      const double opening = std::max(setting, 0.0);
      // The tailwater controls the head only once it rises above the gate lip (submerged flow).
      const double head = upstream_m >= downstream_m
                              ? upstream_m - std::max(downstream_m, opening)
                              : -(downstream_m - std::max(upstream_m, opening));
      return s.coefficient * s.width_m * opening * std::sqrt(2.0 * kGravity) * SignedRootHead(head);
    }
    case Structure::Type::kWeir:
      if (upstream_m >= downstream_m) {
        return WeirOneWay(s.coefficient, s.width_m, setting, upstream_m, downstream_m);
      }
      return -WeirOneWay(s.coefficient, s.width_m, setting, downstream_m, upstream_m);
  }
  return 0.0;
}

double OfftakeFlow(const Offtake& offtake, double setting, double depth_m) {
  switch (offtake.type) {
    case Offtake::Type::kNone:
      return 0.0;
    case Offtake::Type::kFixedFlow: {
      // Fades out over the last centimetre above the outlet so that a drained pool stops giving.
      const double head = depth_m - offtake.outlet_m;
      if (head <= 0.0) return 0.0;
      return head >= 0.01 ? setting : setting * head / 0.01;
    }
    case Offtake::Type::kOrifice: {
      const double head = depth_m - offtake.outlet_m;
      if (head <= 0.0) return 0.0;
      return offtake.coefficient * setting * std::sqrt(2.0 * kGravity) * SignedRootHead(head);
    }
  }
  return 0.0;
}

std::vector<double> SteadyPoolFlows(const Canal& canal) {
  std::vector<double> pool_flow;
  pool_flow.reserve(canal.pools.size());
  double flow = canal.upstream.flow_m3s;
  for (const Pool& pool : canal.pools) {
    pool_flow.push_back(flow);
    flow -= OfftakeFlow(pool.offtake, pool.offtake.setting, pool.target_depth_m);
    if (flow < 0.0) {
      std::ostringstream os;
      os << "pool " << pool.name << ": offtakes take more than the inflow "
         << canal.upstream.flow_m3s << " m3/s at the steady state";
      throw std::invalid_argument(os.str());
    }
  }
  return pool_flow;
}

double SteadyStructureSetting(const Structure& s, double flow_m3s, double upstream_m,
                              double downstream_m) {
  if (s.type == Structure::Type::kPump) return flow_m3s;
  std::ostringstream os;
  os << "no " << (s.type == Structure::Type::kWeir ? "weir crest" : "gate opening") << " passes "
     << flow_m3s << " m3/s with upstream level " << upstream_m << " m and downstream level "
     << downstream_m << " m above the sill";
  if (!(flow_m3s > 0.0) || !(upstream_m > downstream_m) || !(upstream_m > 0.0)) {
    throw std::invalid_argument(os.str());
  }
  // Flow rises with the gate opening and falls with the weir crest; bracket and bisect.
  // A gate passes the most water at an opening of 2/3 of the upstream depth in free flow, or at
  // the tailwater depth when submerged; below that the flow rises monotonically with the opening.
  double lo = 0.0;
  double hi = std::max(downstream_m, 2.0 * upstream_m / 3.0);
  if (s.type == Structure::Type::kWeir) {
    lo = -10.0 * upstream_m - 10.0;
    hi = upstream_m;
  }
  auto excess = [&](double x) { return StructureFlow(s, x, upstream_m, downstream_m) - flow_m3s; };
  double f_lo = excess(lo);
  double f_hi = excess(hi);
  if (f_lo * f_hi > 0.0) throw std::invalid_argument(os.str());
  for (int i = 0; i < 200 && hi - lo > 1e-13; ++i) {
    const double mid = 0.5 * (lo + hi);
    const double f_mid = excess(mid);
    if ((f_mid > 0.0) == (f_lo > 0.0)) {
      lo = mid;
      f_lo = f_mid;
    } else {
      hi = mid;
    }
  }
  (void)f_hi;
  return 0.5 * (lo + hi);
}

}  // namespace canalid::sim
