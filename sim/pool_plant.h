#pragma once
#include <deque>
#include <memory>
#include <utility>

#include "sim/canal.h"

namespace canalid::sim {

class SaintVenantCanal;

/// One pool seen as identification sees it: inflow and outflow in (m^3/s), downstream level out
/// (m).  Flows set by SetFlows hold from the current time until changed (zero-order hold).
/// Shared by the Saint-Venant pool and the fast transfer-function plants for unit tests.
class PoolPlant {
 public:
  virtual ~PoolPlant() = default;
  virtual void SetFlows(double inflow_m3s, double outflow_m3s) = 0;
  /// @throws std::invalid_argument if dt_s <= 0.
  virtual void Step(double dt_s) = 0;
  virtual double time_s() const = 0;
  virtual double level_m() const = 0;
};

/// The inflow history a delayed plant needs: u(t - delay) as a piecewise-constant function.
class DelayedInput final {
 public:
  DelayedInput(double delay_s, double initial);
  /// The input takes `value` from time `t_s` on (t_s not before the previous change).
  void Set(double t_s, double value);
  /// Calls piece(duration_s, value) for the pieces of u(s - delay), s in [t0_s, t1_s], in order.
  template <typename Piece>
  void ForEachPiece(double t0_s, double t1_s, Piece&& piece) const;
  /// Drops changes that can no longer matter before time t_s.
  void Forget(double t_s);
  /// u(t_s - delay), right-continuous.
  double At(double t_s) const;

 private:
  double delay_s_;
  std::deque<std::pair<double, double>> changes_;  // (time the input changed, new value)
};

/// Integrator-delay-zero plant (Litrico & Fromion 2004) around a level y0 and flow q0:
///   y(s) - y0 = (1/(A s) + p21) e^{-tau s} dq_in(s) - (1/(A s) + p22) dq_out(s).
/// p21 = p22 = 0 gives the integrator-delay (ID) model.  Exact for held inputs at any step.
class IdzPlant final : public PoolPlant {
 public:
  /// @throws std::invalid_argument unless delay_s >= 0, area_m2 > 0, p21 >= 0, p22 >= 0.
  IdzPlant(double delay_s, double area_m2, double p21_s_per_m2, double p22_s_per_m2,
           double level0_m, double flow0_m3s);
  void SetFlows(double inflow_m3s, double outflow_m3s) override;
  void Step(double dt_s) override;
  double time_s() const override { return time_s_; }
  double level_m() const override;

 private:
  double area_m2_, p21_, p22_, level0_m_, flow0_m3s_;
  DelayedInput inflow_;
  double outflow_m3s_;
  double time_s_ = 0.0;
  double storage_m_ = 0.0;  // (1/A) * integral of (delayed inflow - outflow) deviations
};

/// First order plus dead time from the inflow to the level (a pool with a self-regulating end):
///   y(s) - y0 = K e^{-tau s} / (1 + T s) * (q_in(s) - q0).   The outflow is ignored.
/// Exact for held inputs at any step.
class FoptdPlant final : public PoolPlant {
 public:
  /// @throws std::invalid_argument unless delay_s >= 0 and time_constant_s > 0.
  FoptdPlant(double gain_m_per_m3s, double time_constant_s, double delay_s, double level0_m,
             double flow0_m3s);
  void SetFlows(double inflow_m3s, double outflow_m3s) override;
  void Step(double dt_s) override;
  double time_s() const override { return time_s_; }
  double level_m() const override { return level0_m_ + gain_ * state_; }

 private:
  double gain_, time_constant_s_, level0_m_, flow0_m3s_;
  DelayedInput inflow_;
  double time_s_ = 0.0;
  double state_ = 0.0;
};

/// One Saint-Venant pool (SaintVenantCanal) with the inflow as upstream boundary and a held
/// outflow at its downstream end, starting at the steady state for `flow_m3s` and the pool's
/// target depth.  level_m() is the downstream depth.
class SaintVenantPool final : public PoolPlant {
 public:
  /// @throws as SaintVenantCanal.
  SaintVenantPool(const Pool& pool, double flow_m3s, double max_dx_m, double theta);
  ~SaintVenantPool() override;
  void SetFlows(double inflow_m3s, double outflow_m3s) override;
  void Step(double dt_s) override;
  double time_s() const override;
  double level_m() const override;
  const SaintVenantCanal& canal() const { return *canal_; }

 private:
  std::unique_ptr<SaintVenantCanal> canal_;
};

template <typename Piece>
void DelayedInput::ForEachPiece(double t0_s, double t1_s, Piece&& piece) const {
  double start = t0_s;
  double value = At(t0_s);
  for (const auto& [t, v] : changes_) {
    const double shifted = t + delay_s_;
    if (shifted <= t0_s) continue;
    if (shifted >= t1_s) break;
    piece(shifted - start, value);
    start = shifted;
    value = v;
  }
  piece(t1_s - start, value);
}

}  // namespace canalid::sim
