#pragma once
#include <Eigen/Core>

#include "core/linear/process_models.h"
#include "core/signal/delayed_zoh.h"
#include "sim/sampled_plant.h"

namespace canalid::sim {

/// Second order plus dead time G(s) = K e^{-tau s} / ((1 + T1 s)(1 + T2 s)) around an operating
/// point, started at rest at the initial input u0 (the convention of `canalid simulate` for soptd
/// records):
///   y = output_offset + K (u0 - input_offset) + G(s) (u - u0).
/// Realised as the cascade x1' = (K du - x1)/T1, x2' = (x1 - x2)/T2, y = x2, discretised exactly
/// for inputs held over each sample with the sub-sample delay (core::DelayedZoh): no
/// approximation, T1 == T2 included.  One input.  Allocates only in the constructor (a ring of
/// floor(tau / Ts) + 2 past inputs).
class SoptdPlant final : public SampledPlant {
 public:
  /// @throws std::invalid_argument unless both time constants are > 0 and finite, the delay is
  ///         >= 0 and finite, sample_time_s > 0 and the gain is finite.
  SoptdPlant(const core::SoptdModel& model, double sample_time_s, double input_offset,
             double output_offset, double initial_input);
  double sample_time_s() const override { return sample_time_s_; }
  int input_count() const override { return 1; }
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

 private:
  double Past(int age) const;  // u[k - age] - u0 after the current input was pushed
  core::DelayedZoh<2> system_;
  double sample_time_s_, initial_input_, level_;
  Eigen::Vector2d state_ = Eigen::Vector2d::Zero();
  Eigen::VectorXd ring_;  // deviations u[k] .. u[k - d - 1], newest at head_
  Eigen::Index head_ = 0;
};

}  // namespace canalid::sim
