#include "sim/saint_venant.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/numerics/check.h"
#include "sim/backwater.h"

namespace canalid::sim {
namespace {

// Newton stops when no depth moves more than this (m) and no flow more than kFlowTol (m^3/s);
// both are far below anything a sensor can see and keep the mass error at round-off level.
constexpr double kDepthTol = 1e-10;
constexpr double kFlowTol = 1e-9;
constexpr int kMaxIterations = 30;
// Levels below which a tailwater does not influence a structure (free outfall).
constexpr double kFreeOutfall = -1e3;
// Step for the numerical derivatives of structure and offtake laws (m).
constexpr double kDiffStep = 1e-7;

}  // namespace

SaintVenantCanal::SaintVenantCanal(const Canal& canal) : canal_(canal) {
  ValidateCanal(canal_);
  const int pools = num_pools();
  offset_.assign(static_cast<std::size_t>(pools) + 1, 0);
  for (int p = 0; p < pools; ++p) {
    const Pool& pool = canal_.pools[static_cast<std::size_t>(p)];
    sections_.emplace_back(pool.bottom_width_m, pool.side_slope, pool.manning_n);
    const int cells = static_cast<int>(std::ceil(pool.length_m / canal_.max_dx_m - 1e-9));
    dx_.push_back(pool.length_m / std::max(cells, 1));
    offset_[static_cast<std::size_t>(p) + 1] =
        offset_[static_cast<std::size_t>(p)] + std::max(cells, 1) + 1;
    structure_setting_.push_back(pool.structure.setting);
    offtake_setting_.push_back(pool.offtake.setting);
  }
  const int n = 2 * offset_[static_cast<std::size_t>(pools)];
  x_.setZero(n);
  guess_.setZero(n);
  residual_.setZero(n);
  delta_.setZero(n);
  friction_.setZero(n / 2, 3);
  old_friction_.setZero(n / 2);
  jacobian_ = NodeChainMatrix(n / 2);
  BuildSteadyState();
  for (const LevelControl& c : canal_.level_controls) {
    LevelPidConfig config = c.pid;
    const int level_pool = FindPoolIndex(canal_, c.level_pool);
    const int actuator = c.actuator_pool.empty() ? -1 : FindPoolIndex(canal_, c.actuator_pool);
    // A pump upstream of the held pool fills it; the pool's own pump, or one below, drains it.
    config.direct_action = actuator < level_pool;
    BoundControl bound{LevelPid(config), level_pool, c.level_downstream, actuator, 0};
    controls_.push_back(bound);
    const int k = static_cast<int>(controls_.size()) - 1;
    const double flow =
        actuator < 0 ? upstream_value_ : structure_setting_[static_cast<std::size_t>(actuator)];
    controls_[static_cast<std::size_t>(k)].pid.Reset(flow, ControlledLevel(k));
  }
  old_x_ = x_;
  initial_volume_m3_ = Volume();
  boundary_ = CurrentBoundaryFlows();
}

SaintVenantCanal::BoundaryFlows SaintVenantCanal::CurrentBoundaryFlows() const {
  BoundaryFlows b;
  b.inflow_m3s = PoolInflow(0);
  for (int p = 0; p < num_pools(); ++p) b.offtake_m3s += OfftakeFlow(p);
  b.outflow_m3s = StructureFlow(num_pools() - 1);
  return b;
}

double SaintVenantCanal::TailLevel(int pool) const {
  const double tail = canal_.pools[static_cast<std::size_t>(pool)].structure.tailwater_m;
  return tail < 0.0 ? kFreeOutfall : tail;
}

void SaintVenantCanal::BuildSteadyState() {
  const int pools = num_pools();
  const std::vector<double> pool_flow = SteadyPoolFlows(canal_);
  for (int p = 0; p < pools; ++p) {
    std::vector<double> depth;
    try {
      depth = SteadyProfile(canal_.pools[static_cast<std::size_t>(p)],
                            pool_flow[static_cast<std::size_t>(p)], num_nodes(p) - 1,
                            canal_.pools[static_cast<std::size_t>(p)].target_depth_m);
    } catch (const std::runtime_error& e) {
      // No steady state for these flows and targets: a problem of the configuration.
      throw std::invalid_argument(e.what());
    }
    for (int i = 0; i < num_nodes(p); ++i) {
      x_[DepthIndex(p, i)] = depth[static_cast<std::size_t>(i)];
      x_[DepthIndex(p, i) + 1] = pool_flow[static_cast<std::size_t>(p)];
    }
  }
  for (int p = 0; p < pools; ++p) {
    const Pool& pool = canal_.pools[static_cast<std::size_t>(p)];
    const double through =
        p + 1 < pools
            ? pool_flow[static_cast<std::size_t>(p) + 1]
            : pool_flow[static_cast<std::size_t>(p)] -
                  sim::OfftakeFlow(pool.offtake, offtake_setting_[static_cast<std::size_t>(p)],
                                   pool.target_depth_m);
    const double down = p + 1 < pools ? UpstreamDepth(p + 1) - pool.structure.drop_m : TailLevel(p);
    if (pool.structure.setting_from_steady_state) {
      try {
        structure_setting_[static_cast<std::size_t>(p)] =
            SteadyStructureSetting(pool.structure, through, DownstreamDepth(p), down);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("pool " + pool.name + " structure: " + e.what());
      }
    }
  }
  upstream_value_ = canal_.upstream.type == UpstreamBoundary::Type::kFlow ? canal_.upstream.flow_m3s
                                                                          : UpstreamDepth(0);
}

double SaintVenantCanal::ControlledLevel(int k) const {
  const BoundControl& c = controls_.at(static_cast<std::size_t>(k));
  return c.level_downstream ? DownstreamDepth(c.level_pool) : UpstreamDepth(c.level_pool);
}

void SaintVenantCanal::RunLevelControls() {
  for (int k = 0; k < num_level_controls(); ++k) {
    BoundControl& c = controls_[static_cast<std::size_t>(k)];
    // Sample instants are compared with a tolerance so that k Ts is not missed by rounding.
    const double eps = 1e-9 * (1.0 + time_s_);
    const double ts = c.pid.config().sample_time_s;
    if (time_s_ + eps >= static_cast<double>(c.next_sample) * ts) {
      c.pid.Update(ControlledLevel(k));
      c.next_sample = static_cast<long>(std::floor((time_s_ + eps) / ts)) + 1;
    }
    // Held between samples, and it overrides any setting written to the pump from outside.
    if (c.actuator_pool < 0) {
      upstream_value_ = c.pid.output_m3s();
    } else {
      structure_setting_[static_cast<std::size_t>(c.actuator_pool)] = c.pid.output_m3s();
    }
  }
}

double SaintVenantCanal::StructureFlow(int pool) const {
  if (pool + 1 < num_pools()) return PoolInflow(pool + 1);
  return PoolOutflow(pool) - OfftakeFlow(pool);
}

double SaintVenantCanal::OfftakeFlow(int pool) const {
  return sim::OfftakeFlow(canal_.pools[static_cast<std::size_t>(pool)].offtake,
                          offtake_setting_[static_cast<std::size_t>(pool)], DownstreamDepth(pool));
}

double SaintVenantCanal::PoolVolume(int pool) const {
  const TrapezoidSection& s = sections_[static_cast<std::size_t>(pool)];
  double sum = 0.0;
  const int n = num_nodes(pool);
  for (int i = 0; i < n; ++i) {
    const double a = s.Area(depth_m(pool, i));
    sum += (i == 0 || i == n - 1) ? 0.5 * a : a;
  }
  return sum * dx_[static_cast<std::size_t>(pool)];
}

double SaintVenantCanal::Volume() const {
  double v = 0.0;
  for (int p = 0; p < num_pools(); ++p) v += PoolVolume(p);
  return v;
}

void SaintVenantCanal::Add(int row, int col, double value) { jacobian_.Set(row, col, value); }

void SaintVenantCanal::NodeFriction(const Eigen::VectorXd& x, Eigen::MatrixX3d* all,
                                    Eigen::VectorXd* g_only) const {
  for (int p = 0; p < num_pools(); ++p) {
    const TrapezoidSection& s = sections_[static_cast<std::size_t>(p)];
    for (int j = offset_[static_cast<std::size_t>(p)]; j < offset_[static_cast<std::size_t>(p) + 1];
         ++j) {
      double g = 0.0, g_h = 0.0, g_q = 0.0;
      const Eigen::Index h = 2 * Eigen::Index{j};
      s.Friction(x[h], x[h + 1], &g, &g_h, &g_q);
      if (all != nullptr) all->row(j) << g, g_h, g_q;
      if (g_only != nullptr) (*g_only)(j) = g;
    }
  }
}

void SaintVenantCanal::Assemble(const Eigen::VectorXd& old_x, double dt_s) {
  NodeFriction(x_, &friction_, nullptr);
  const double theta = canal_.theta;
  const double g = kGravity;
  jacobian_.SetZero();
  int row = 0;
  // Upstream boundary.
  if (canal_.upstream.type == UpstreamBoundary::Type::kFlow) {
    residual_[row] = x_[1] - upstream_value_;
    Add(row, 1, 1.0);
  } else {
    residual_[row] = x_[0] - upstream_value_;
    Add(row, 0, 1.0);
  }
  ++row;
  const int pools = num_pools();
  for (int p = 0; p < pools; ++p) {
    const TrapezoidSection& s = sections_[static_cast<std::size_t>(p)];
    const double dx = dx_[static_cast<std::size_t>(p)];
    const double slope = canal_.pools[static_cast<std::size_t>(p)].bed_slope;
    for (int j = offset_[static_cast<std::size_t>(p)];
         j + 1 < offset_[static_cast<std::size_t>(p) + 1]; ++j) {
      const int hl = 2 * j, ql = hl + 1, hr = hl + 2, qr = hl + 3;
      const double hl1 = x_[hl], ql1 = x_[ql], hr1 = x_[hr], qr1 = x_[qr];
      const double hl0 = old_x[hl], ql0 = old_x[ql], hr0 = old_x[hr], qr0 = old_x[qr];
      const double al1 = s.Area(hl1), ar1 = s.Area(hr1), al0 = s.Area(hl0), ar0 = s.Area(hr0);
      const double tl1 = s.TopWidth(hl1), tr1 = s.TopWidth(hr1);
      // Continuity.
      residual_[row] = (al1 + ar1 - al0 - ar0) / (2.0 * dt_s) +
                       (theta * (qr1 - ql1) + (1.0 - theta) * (qr0 - ql0)) / dx;
      Add(row, hl, tl1 / (2.0 * dt_s));
      Add(row, ql, -theta / dx);
      Add(row, hr, tr1 / (2.0 * dt_s));
      Add(row, qr, theta / dx);
      ++row;
      // Momentum; z differences include the bed: z_r - z_l = h_r - h_l - S0 dx.
      // Friction per node (NodeFriction): the new level's of this iteration, the old level's of
      // this step.
      const double gl1 = friction_(j, 0), gl1h = friction_(j, 1), gl1q = friction_(j, 2);
      const double gr1 = friction_(j + 1, 0), gr1h = friction_(j + 1, 1),
                   gr1q = friction_(j + 1, 2);
      const double gl0 = old_friction_(j), gr0 = old_friction_(j + 1);
      const double fl1 = ql1 * ql1 / al1, fr1 = qr1 * qr1 / ar1;
      const double fl0 = ql0 * ql0 / al0, fr0 = qr0 * qr0 / ar0;
      const double abar = 0.5 * theta * (al1 + ar1) + 0.5 * (1.0 - theta) * (al0 + ar0);
      const double dz = theta * (hr1 - hl1) + (1.0 - theta) * (hr0 - hl0) - slope * dx;
      residual_[row] = (ql1 + qr1 - ql0 - qr0) / (2.0 * dt_s) +
                       (theta * (fr1 - fl1) + (1.0 - theta) * (fr0 - fl0)) / dx +
                       g * abar * dz / dx +
                       0.5 * g * (theta * (gl1 + gr1) + (1.0 - theta) * (gl0 + gr0));
      const double dfl_dh = -fl1 * tl1 / al1, dfr_dh = -fr1 * tr1 / ar1;
      Add(row, hl,
          -theta * dfl_dh / dx + 0.5 * g * theta * tl1 * dz / dx - g * abar * theta / dx +
              0.5 * g * theta * gl1h);
      Add(row, ql, 1.0 / (2.0 * dt_s) - theta * 2.0 * ql1 / al1 / dx + 0.5 * g * theta * gl1q);
      Add(row, hr,
          theta * dfr_dh / dx + 0.5 * g * theta * tr1 * dz / dx + g * abar * theta / dx +
              0.5 * g * theta * gr1h);
      Add(row, qr, 1.0 / (2.0 * dt_s) + theta * 2.0 * qr1 / ar1 / dx + 0.5 * g * theta * gr1q);
      ++row;
    }
    // Downstream end of the pool: offtake and structure.
    const Pool& pool = canal_.pools[static_cast<std::size_t>(p)];
    const int a = offset_[static_cast<std::size_t>(p) + 1] - 1;
    const int ha = 2 * a, qa = ha + 1;
    const double h = x_[ha];
    const double off =
        sim::OfftakeFlow(pool.offtake, offtake_setting_[static_cast<std::size_t>(p)], h);
    const double off_h =
        (sim::OfftakeFlow(pool.offtake, offtake_setting_[static_cast<std::size_t>(p)],
                          h + kDiffStep) -
         sim::OfftakeFlow(pool.offtake, offtake_setting_[static_cast<std::size_t>(p)],
                          h - kDiffStep)) /
        (2.0 * kDiffStep);
    const Structure& st = pool.structure;
    const double setting = structure_setting_[static_cast<std::size_t>(p)];
    if (p + 1 < pools) {
      const int hb = ha + 2, qb = ha + 3;
      const double down = x_[hb] - st.drop_m;
      residual_[row] = x_[qa] - off - x_[qb];
      Add(row, ha, -off_h);
      Add(row, qa, 1.0);
      Add(row, qb, -1.0);
      ++row;
      const double f = sim::StructureFlow(st, setting, h, down);
      const double f_up = (sim::StructureFlow(st, setting, h + kDiffStep, down) -
                           sim::StructureFlow(st, setting, h - kDiffStep, down)) /
                          (2.0 * kDiffStep);
      const double f_dn = (sim::StructureFlow(st, setting, h, down + kDiffStep) -
                           sim::StructureFlow(st, setting, h, down - kDiffStep)) /
                          (2.0 * kDiffStep);
      residual_[row] = x_[qb] - f;
      Add(row, ha, -f_up);
      Add(row, hb, -f_dn);
      Add(row, qb, 1.0);
      ++row;
    } else {
      const double tail = TailLevel(p);
      const double f = sim::StructureFlow(st, setting, h, tail);
      const double f_up = (sim::StructureFlow(st, setting, h + kDiffStep, tail) -
                           sim::StructureFlow(st, setting, h - kDiffStep, tail)) /
                          (2.0 * kDiffStep);
      residual_[row] = x_[qa] - off - f;
      Add(row, ha, -off_h - f_up);
      Add(row, qa, 1.0);
      ++row;
    }
  }
  CANALID_DEMAND(row == residual_.size(), "one equation per unknown");
}

bool SaintVenantCanal::Newton(const Eigen::VectorXd& start, double dt_s, int* iterations) {
  x_ = start;
  for (Eigen::Index k = 0; k < x_.size(); k += 2) x_[k] = std::max(x_[k], 1e-4);
  bool converged = false;
  int it = 0;
  for (; it < kMaxIterations && !converged; ++it) {
    Assemble(old_x_, dt_s);
    delta_ = -residual_;
    if (!jacobian_.SolveInPlace(delta_)) break;
    converged = true;
    for (Eigen::Index k = 0; k < delta_.size(); k += 2) {
      if (std::abs(delta_[k]) > kDepthTol || std::abs(delta_[k + 1]) > kFlowTol) {
        converged = false;
      }
    }
    x_ += delta_;
    for (Eigen::Index k = 0; k < x_.size(); k += 2) x_[k] = std::max(x_[k], 1e-4);
  }
  *iterations = it;
  return converged && x_.allFinite();
}

void SaintVenantCanal::Step(double dt_s) {
  if (!(dt_s > 0.0)) {
    throw std::invalid_argument("SaintVenantCanal::Step: dt_s " + std::to_string(dt_s) +
                                " must be > 0");
  }
  RunLevelControls();
  // Newton starts from the state extrapolated along the last step's change (old_x_ still holds
  // the state before it), closer than the last state by the order of the step: on canal 2 at
  // dt 10 s, 3.0 iterations a step become 2.5.  The converged state is the same to the Newton
  // tolerance.  A longer step than the last extrapolates no further than one step's change;
  // where the extrapolation overshoots (a sudden change of an input), Newton starts again from
  // the last state.
  const double ratio = last_dt_s_ > 0.0 ? std::min(dt_s / last_dt_s_, 1.0) : 0.0;
  guess_ = x_ + ratio * (x_ - old_x_);
  old_x_ = x_;
  NodeFriction(old_x_, nullptr, &old_friction_);
  int iterations = 0;
  bool converged = Newton(guess_, dt_s, &iterations);
  if (!converged && ratio > 0.0) {
    int again = 0;
    converged = Newton(old_x_, dt_s, &again);
    iterations += again;
  }
  last_iterations_ = iterations;
  if (!converged) {
    x_ = old_x_;  // the state before the step (the level controls have sampled)
    last_dt_s_ = 0.0;
    std::ostringstream os;
    os << "SaintVenantCanal: Newton did not converge in " << kMaxIterations
       << " iterations at t = " << time_s_ + dt_s << " s (dt " << dt_s << " s)";
    throw std::runtime_error(os.str());
  }
  time_s_ += dt_s;
  last_dt_s_ = dt_s;
  // Boundary flows of the previous step were stored then: an input changed since then (an
  // offtake setting) must not be counted at the old time level.
  const BoundaryFlows now = CurrentBoundaryFlows();
  mass_.inflow_volume_m3 += 0.5 * dt_s * (boundary_.inflow_m3s + now.inflow_m3s);
  mass_.offtake_volume_m3 += 0.5 * dt_s * (boundary_.offtake_m3s + now.offtake_m3s);
  mass_.outflow_volume_m3 += 0.5 * dt_s * (boundary_.outflow_m3s + now.outflow_m3s);
  boundary_ = now;
  mass_.volume_change_m3 = Volume() - initial_volume_m3_;
  mass_.error_m3 = mass_.volume_change_m3 -
                   (mass_.inflow_volume_m3 - mass_.offtake_volume_m3 - mass_.outflow_volume_m3);
  mass_.relative_error =
      mass_.inflow_volume_m3 > 0.0 ? std::abs(mass_.error_m3) / mass_.inflow_volume_m3 : 0.0;
}

}  // namespace canalid::sim
