#pragma once
#include <Eigen/Core>

#include "core/fractional/lpv_model.h"
#include "sim/sampled_plant.h"

namespace canalid::sim {

/// The first-order ARX LPV model of `canalid identify --model lpv --local arx`, run along a
/// scheduling trajectory with the conventions of core::SimulateLpvArx (and `canalid simulate`):
///   y[k] = output_offset + dy[k],  dy[0] = 0,
///   dy[k] = -a1(theta[k]) dy[k-1] + b1(theta[k]) du[k - nk(theta[k])],  k >= 1,
///   du = u - input_offset (zero before sample 0),  nk(theta) = max(1, round(poly(theta))),
/// with a1, b1, nk the model's polynomials in theta.  Two inputs: (u, theta), the scheduling
/// variable held over the sample like u.  y[k] depends on theta[k] (direct feedthrough of the
/// schedule), not on u[k].  Keeps the last max_delay_samples inputs; no allocation after
/// construction.
class LpvArxPlant final : public SampledPlant {
 public:
  /// @param max_delay_samples the longest delay the plant can apply (>= 1): a theta whose
  ///        nk(theta) exceeds it makes Output/Advance throw.
  /// @throws std::invalid_argument if the model is not first_order_arx (3 polynomials),
  ///         sample_time_s <= 0 or max_delay_samples < 1.
  LpvArxPlant(const core::LpvModel& model, double sample_time_s, double input_offset,
              double output_offset, int max_delay_samples);
  double sample_time_s() const override { return sample_time_s_; }
  int input_count() const override { return 2; }
  /// @throws std::invalid_argument on a wrong input size, or a theta whose delay is longer than
  ///         max_delay_samples (the message gives both).
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

  /// max(1, round(nk(theta))), unchecked against max_delay_samples.
  long DelaySamples(double theta) const;

 private:
  double Deviation(const Eigen::Ref<const Eigen::VectorXd>& inputs) const;  // dy[k]
  core::LpvModel model_;
  double sample_time_s_, input_offset_, output_offset_;
  Eigen::VectorXd inputs_;  // du[k-1] .. du[k - max_delay], newest at head_
  Eigen::Index head_ = 0;
  Eigen::Index sample_ = 0;
  double previous_ = 0.0;  // dy[k-1]
};

}  // namespace canalid::sim
