#pragma once
#include <Eigen/Core>

#include "core/fractional/commensurate_state_space.h"
#include "sim/sampled_plant.h"

namespace canalid::sim {

/// The LPV paper's commensurate fractional state space
/// (core/fractional/commensurate_state_space.h), alpha = 1/q, n = 2q states, run sample by sample
/// with the recursion of core::SimulateCommensurate:
///   x[k+1] = A x[k] + B du[k - nk] - sum_{j=1..min(k+1, L)} w_j x[k+1-j],  y[k] = C x[k],
/// w_j the Grunwald-Letnikov weights of order alpha.  Unit static gain, started at rest at u0
/// (the convention of `canalid simulate` for frac-ss records):
///   y = output_offset + (u0 - input_offset) + model(u - u0).
/// memory_length L > 0 keeps the last L states (a fixed ring, no allocation after construction,
/// O(L n) work per sample).  L = 0 is the full memory of `canalid simulate` on a whole record: the
/// state history then grows with the run (capacity doubled when full, so allocations are
/// O(log k)) and each sample costs O(k n); give L for long runs.  One input.
class CommensuratePlant final : public SampledPlant {
 public:
  /// @param expected_samples initial history capacity when memory_length = 0 (ignored otherwise).
  /// @throws std::invalid_argument on an invalid model (core::Validate), memory_length < 0 or
  ///         sample_time_s <= 0.
  CommensuratePlant(const core::CommensurateModel& model, int memory_length, double sample_time_s,
                    double input_offset, double output_offset, double initial_input,
                    Eigen::Index expected_samples = 1024);
  double sample_time_s() const override { return sample_time_s_; }
  int input_count() const override { return 1; }
  double Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const override;
  void Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) override;

 private:
  void Grow();  // full memory only: doubles the history and the weights
  core::CommensurateModel model_;
  int memory_length_;
  double sample_time_s_, initial_input_, level_;
  Eigen::VectorXd weights_;  // w_0 .. w_capacity
  Eigen::MatrixXd history_;  // column k mod capacity = x[k]
  Eigen::VectorXd state_;    // x[k]
  Eigen::VectorXd next_;
  Eigen::VectorXd inputs_;  // deviations du[k] .. du[k - nk], newest at input_head_
  Eigen::Index input_head_ = 0;
  Eigen::Index sample_ = 0;
};

}  // namespace canalid::sim
