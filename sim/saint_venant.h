#pragma once
#include <Eigen/Core>
#include <vector>

#include "sim/canal.h"
#include "sim/hydraulics.h"
#include "sim/level_pid.h"
#include "sim/node_chain_matrix.h"

namespace canalid::sim {

/// Volume accounting since construction (m^3).  `error_m3` = volume change - net boundary volume,
/// where the boundary flows (upstream inflow, offtakes, outflow of the last pool) are integrated
/// with the trapezoidal rule over each time step.
struct MassBalance {
  double volume_change_m3 = 0.0;
  double inflow_volume_m3 = 0.0;
  double offtake_volume_m3 = 0.0;
  double outflow_volume_m3 = 0.0;
  double error_m3 = 0.0;
  /// |error| / inflow volume (0 if no inflow yet).
  double relative_error = 0.0;
};

/// Unsteady open-channel flow in a chain of pools: the 1-D Saint-Venant equations
///   dA/dt + dQ/dx = 0,   dQ/dt + d(Q^2/A)/dx + g A dz/dx + g A Sf = 0,   Sf = n^2 Q|Q|/(A^2 R^4/3)
/// with z the water surface elevation, discretised with the Preissmann four-point box scheme
/// (space weight 1/2, time weight theta) and solved at each step by Newton iterations on all the
/// depths and flows at once.  With depths and flows interleaved (h0, Q0, h1, Q1, ...) and one
/// row per equation in the same order, the first equation involves the first node only, each
/// next pair of equations two neighbouring nodes, and the last one the last node: the Jacobian
/// is a chain of 2 x 2 blocks, solved by a double sweep (NodeChainMatrix).  Newton starts from
/// the state extrapolated along the last step.
/// The structure between two pools adds two algebraic equations (flow continuity with the
/// offtake, structure law); the upstream end takes a flow or a level, the downstream end of the
/// last pool its structure law against the tailwater.
/// Construction starts from the steady state for `canal.upstream.flow_m3s` and the pools'
/// target depths (SteadyProfile), with the structure settings that hold it where asked.
/// The canal's level controls (LevelControl) run inside Step: at each of their sample instants
/// (t = 0, Ts, 2 Ts, ..., taken at the first step starting at or after it) they read the held
/// depth and set their pump's flow, which then holds until the next sample; they start bumpless
/// from the steady flow.
/// Not thread-safe.  Allocates only in the constructor.
class SaintVenantCanal final {
 public:
  /// @throws std::invalid_argument if the canal is invalid (ValidateCanal) or has no steady state
  /// for its flows and target depths (supercritical profile, a structure that cannot pass its
  /// flow at the steady levels).
  explicit SaintVenantCanal(const Canal& canal);

  /// Advances by dt_s with the inputs set now taken as the values at the end of the step.
  /// @throws std::runtime_error if Newton does not converge (the message gives the time); the
  /// depths and flows are then those before the step (the level controls have taken their
  /// sample).
  void Step(double dt_s);

  /// Inflow (m^3/s) or reservoir depth (m), according to canal().upstream.type.
  void SetUpstream(double value) { upstream_value_ = value; }
  double upstream() const { return upstream_value_; }
  void SetStructureSetting(int pool, double setting) {
    structure_setting_.at(static_cast<std::size_t>(pool)) = setting;
  }
  double structure_setting(int pool) const {
    return structure_setting_.at(static_cast<std::size_t>(pool));
  }
  void SetOfftakeSetting(int pool, double setting) {
    offtake_setting_.at(static_cast<std::size_t>(pool)) = setting;
  }
  double offtake_setting(int pool) const {
    return offtake_setting_.at(static_cast<std::size_t>(pool));
  }

  const Canal& canal() const { return canal_; }
  double time_s() const { return time_s_; }
  int num_pools() const { return static_cast<int>(canal_.pools.size()); }
  int num_nodes(int pool) const {
    return offset_.at(static_cast<std::size_t>(pool) + 1) -
           offset_.at(static_cast<std::size_t>(pool));
  }
  double dx_m(int pool) const { return dx_.at(static_cast<std::size_t>(pool)); }
  double depth_m(int pool, int node) const { return x_[DepthIndex(pool, node)]; }
  double flow_m3s(int pool, int node) const { return x_[DepthIndex(pool, node) + 1]; }
  double PoolInflow(int pool) const { return flow_m3s(pool, 0); }
  /// Flow leaving the pool at its downstream end (structure flow plus offtake).
  double PoolOutflow(int pool) const { return flow_m3s(pool, num_nodes(pool) - 1); }
  double UpstreamDepth(int pool) const { return depth_m(pool, 0); }
  double DownstreamDepth(int pool) const { return depth_m(pool, num_nodes(pool) - 1); }
  double StructureFlow(int pool) const;
  double OfftakeFlow(int pool) const;
  /// Water volume of a pool (m^3), trapezoidal rule over the nodes.
  double PoolVolume(int pool) const;
  double Volume() const;
  const MassBalance& mass_balance() const { return mass_; }
  int num_level_controls() const { return static_cast<int>(controls_.size()); }
  const LevelPid& level_control(int k) const {
    return controls_.at(static_cast<std::size_t>(k)).pid;
  }
  /// Depth (m) the control `k` holds, now.
  double ControlledLevel(int k) const;
  void SetLevelSetpoint(int k, double setpoint_m) {
    controls_.at(static_cast<std::size_t>(k)).pid.SetSetpoint(setpoint_m);
  }
  int last_iterations() const { return last_iterations_; }

 private:
  struct BoundaryFlows {
    double inflow_m3s = 0.0;
    double offtake_m3s = 0.0;
    double outflow_m3s = 0.0;
  };
  BoundaryFlows CurrentBoundaryFlows() const;
  void BuildSteadyState();
  void Assemble(const Eigen::VectorXd& old_x, double dt_s);
  /// Newton's iterations from `start` for the step to old_x_ + dt_s, in x_; whether they
  /// converged to finite values.
  bool Newton(const Eigen::VectorXd& start, double dt_s, int* iterations);
  /// Manning friction G = g A Sf of every node at the depths and flows `x`: G, dG/dh and dG/dQ
  /// into the rows of `all`, or G alone into `g_only` (either may be null).  Once per node, where
  /// the segments computed it twice per node and the old level's again at every iteration.
  void NodeFriction(const Eigen::VectorXd& x, Eigen::MatrixX3d* all, Eigen::VectorXd* g_only) const;
  void Add(int row, int col, double value);
  double TailLevel(int pool) const;
  void RunLevelControls();

  struct BoundControl {
    LevelPid pid;
    int level_pool = 0;
    bool level_downstream = true;
    int actuator_pool = -1;  // -1: the upstream inflow
    long next_sample = 0;    // index of the next sample instant
  };

  // Where the depth of a pool's node sits in x_ (its flow is the next entry).
  Eigen::Index DepthIndex(int pool, int node) const {
    return 2 * Eigen::Index{offset_[static_cast<std::size_t>(pool)] + node};
  }

  Canal canal_;
  std::vector<TrapezoidSection> sections_;
  std::vector<int> offset_;  // first node of each pool, plus the total at the end
  std::vector<double> dx_;
  std::vector<double> structure_setting_;
  std::vector<double> offtake_setting_;
  double upstream_value_ = 0.0;
  double time_s_ = 0.0;
  Eigen::VectorXd x_;       // depth and flow interleaved: h0, Q0, h1, Q1, ...
  Eigen::VectorXd old_x_;   // the state at the start of this step (of the last one, between steps)
  Eigen::VectorXd guess_;   // Newton's starting state
  double last_dt_s_ = 0.0;  // the last converged step's length; 0 before the first
  Eigen::VectorXd residual_;
  Eigen::VectorXd delta_;
  Eigen::MatrixX3d friction_;     // per node at x_: G, dG/dh, dG/dQ (this iteration)
  Eigen::VectorXd old_friction_;  // per node at old_x_: G (this step)
  NodeChainMatrix jacobian_{1};
  int last_iterations_ = 0;
  double initial_volume_m3_ = 0.0;
  MassBalance mass_;
  BoundaryFlows boundary_;
  std::vector<BoundControl> controls_;
};

}  // namespace canalid::sim
