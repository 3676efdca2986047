#pragma once
#include <Eigen/Core>
#include <memory>

#include "core/fractional/fractional_foptd.h"
#include "core/fractional/fractional_simulator.h"
#include "core/integrator_delay/integrator_delay_model.h"
#include "core/linear/arx.h"
#include "sim/pool_plant.h"

namespace canalid::sim {

/// A sampled SISO/MISO plant (the shape of every `canalid` model): inputs u[k] are held over
/// [k Ts, (k+1) Ts) (zero-order hold), the output y[k] is at t = k Ts.  Use: y = Output(u[k]),
/// then Advance(u[k]).  Output may depend on u[k] (direct feedthrough, e.g. an ID model with
/// zero delay samples).  No allocation after construction (except CommensuratePlant with full
/// memory, whose history grows with the run).
class SampledPlant {
 public:
  virtual ~SampledPlant() = default;
  virtual double sample_time_s() const = 0;
  virtual int input_count() const = 0;
  /// y[k] given the inputs held from now.  @throws std::invalid_argument on a wrong input size.
  virtual double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const = 0;
  /// From k to k + 1 with `inputs` held over the sample.  @throws as Output.
  virtual void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) = 0;
};

/// Fractional first order plus dead time G(s) = K e^{-tau s} / (1 + T s^alpha) around an
/// operating point, started at rest at the initial input u0:
///   y = output_offset + K (u0 - input_offset) + G(s) (u - u0)
/// (the convention of `canalid simulate` for foptd and frac-foptd records).  Realised by
/// core::OustaloupFoptdSimulator; alpha = 1 is the exact ZOH first order (FOPTD, no
/// approximation).  One input.
class FractionalFoptdPlant final : public SampledPlant {
 public:
  /// @throws std::invalid_argument on invalid params, sample_time_s <= 0 or a bad band.
  FractionalFoptdPlant(const core::FractionalFoptdParams& params,
                       const core::OustaloupOptions& band, double sample_time_s,
                       double input_offset, double output_offset, double initial_input);
  double sample_time_s() const override { return sample_time_s_; }
  int input_count() const override { return 1; }
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

 private:
  core::OustaloupFoptdSimulator simulator_;
  double sample_time_s_, initial_input_, level_;
};

/// The integrator-delay level equation of `canalid identify --model id`
/// (core/integrator_delay/integrator_delay_model.h), and with p22 the IDZ one of `--model idz`
/// (core::IdzLevel, whose q_in(k - nk) term is (p21 - b): give that as p21):
///   Q(k) = Q(k-1) + q_in(k - nk) - q_out(k - 1),  Q(k0 - 1) = 0,
///   y(k) = b Q(k) + p21 q_in(k - nk) - p22 q_out(k) + c + d (k - k0),
/// with inputs (q_in, q_out) in m^3/s and y in m.  The plant's sample 0 is the model's sample 0;
/// inflows before it are `initial_inflow_m3s` (at rest).  Outputs before k0 have Q = 0.
class IntegratorDelayLevelPlant final : public SampledPlant {
 public:
  /// @throws std::invalid_argument unless nk >= 0, Ts > 0, b finite, k0 >= 0.
  IntegratorDelayLevelPlant(const core::IntegratorDelayModel& model, double p21_s_per_m2,
                            double offset_m, double drift_m_per_sample, int fit_from_sample,
                            double initial_inflow_m3s, double p22_s_per_m2 = 0.0);
  double sample_time_s() const override { return model_.sample_time_s; }
  int input_count() const override { return 2; }
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

 private:
  double DelayedInflow(double inflow_now) const;
  core::IntegratorDelayModel model_;
  double p21_, p22_, offset_m_, drift_m_per_sample_;
  int k0_;
  Eigen::VectorXd inflow_history_;  // ring of the last nk inflows (q_in(k - nk) .. q_in(k - 1))
  int head_ = 0;                    // index of q_in(k - nk)
  long sample_ = 0;
  double previous_outflow_m3s_ = 0.0;
  double integrated_m3s_ = 0.0;  // Q(k - 1)
};

/// The ARX model of `canalid identify --model arx` run as a simulation (core::SimulateArx):
///   y(t) = -sum_j a_j y(t-j) + sum_i sum_j b_ij u_i(t - nk_i - j + 1),
/// with inputs before sample 0 taken as 0 and the first outputs given (y(t) = initial_outputs(t)
/// for t < its size, as `canalid simulate` starts from the measured ones).  Any number of inputs.
class ArxPlant final : public SampledPlant {
 public:
  /// @throws std::invalid_argument on sample_time_s <= 0 or orders that disagree with a and b.
  ArxPlant(const core::ArxModel& model, double sample_time_s,
           const Eigen::Ref<const Eigen::VectorXd>& initial_outputs);
  double sample_time_s() const override { return sample_time_s_; }
  int input_count() const override { return static_cast<int>(model_.b.size()); }
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

 private:
  core::ArxModel model_;
  double sample_time_s_;
  Eigen::VectorXd initial_outputs_;
  Eigen::MatrixXd input_ring_;   // row (head - m) mod rows = u(t - m), m = 1..rows
  Eigen::VectorXd output_ring_;  // (head - j) mod na = y(t - j), j = 1..na
  Eigen::Index input_head_ = 0;
  Eigen::Index output_head_ = 0;
  Eigen::Index sample_ = 0;
};

/// A sampled plant seen as a pool (PoolPlant): one input = the inflow (the outflow is ignored),
/// two inputs = (inflow, outflow).  Step(dt) must be a whole number of samples.
class SampledPoolPlant final : public PoolPlant {
 public:
  /// @throws std::invalid_argument if plant is null or has other than 1 or 2 inputs.
  SampledPoolPlant(std::unique_ptr<SampledPlant> plant, double inflow_m3s, double outflow_m3s);
  void SetFlows(double inflow_m3s, double outflow_m3s) override;
  /// @throws std::invalid_argument unless dt_s is a positive whole multiple (1e-9) of Ts.
  void Step(double dt_s) override;
  double time_s() const override { return static_cast<double>(samples_) * plant_->sample_time_s(); }
  double level_m() const override { return plant_->Output(inputs_); }

 private:
  std::unique_ptr<SampledPlant> plant_;
  Eigen::VectorXd inputs_;
  long samples_ = 0;
};

}  // namespace canalid::sim
