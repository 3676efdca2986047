#include "sim/commensurate_plant.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/fractional/grunwald_letnikov.h"

namespace canalid::sim {
namespace {

void RequireOneInput(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  if (inputs.size() != 1) {
    throw std::invalid_argument("CommensuratePlant: inputs has " + std::to_string(inputs.size()) +
                                " values, the plant takes 1");
  }
}

}  // namespace

CommensuratePlant::CommensuratePlant(const core::CommensurateModel& model, int memory_length,
                                     double sample_time_s, double input_offset,
                                     double output_offset, double initial_input,
                                     Eigen::Index expected_samples)
    : model_(model),
      memory_length_(memory_length),
      sample_time_s_(sample_time_s),
      initial_input_(initial_input),
      // Unit static gain: the rest level at u0 is offset by u0 - input_offset itself.
      level_(output_offset + (initial_input - input_offset)) {
  core::Validate(model);
  if (memory_length < 0) {
    throw std::invalid_argument("CommensuratePlant: memory_length = " +
                                std::to_string(memory_length) + ", must be >= 0 (0 = full)");
  }
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
    throw std::invalid_argument(
        "CommensuratePlant: sample_time_s = " + std::to_string(sample_time_s) + ", must be > 0");
  }
  const int n = model.order();
  const Eigen::Index capacity =
      memory_length > 0 ? memory_length : std::max<Eigen::Index>(expected_samples, 16);
  weights_ = core::GrunwaldLetnikovWeights(model.alpha(), static_cast<int>(capacity) + 1);
  history_ = Eigen::MatrixXd::Zero(n, capacity);
  state_ = Eigen::VectorXd::Zero(n);
  next_ = Eigen::VectorXd::Zero(n);
  inputs_ = Eigen::VectorXd::Zero(model.delay_samples + 1);
}

double CommensuratePlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireOneInput(inputs);
  const int n = model_.order();
  return level_ + state_(0) + model_.c.dot(state_.tail(n - 1));
}

void CommensuratePlant::Grow() {
  const Eigen::Index capacity = 2 * history_.cols();
  // Full memory never wraps (column k holds x[k]), so the old columns keep their places.
  history_.conservativeResize(Eigen::NoChange, capacity);
  weights_ = core::GrunwaldLetnikovWeights(model_.alpha(), static_cast<int>(capacity) + 1);
}

void CommensuratePlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  RequireOneInput(inputs);
  const int n = model_.order();
  if (memory_length_ == 0 && sample_ >= history_.cols()) Grow();
  const Eigen::Index capacity = history_.cols();
  history_.col(sample_ % capacity) = state_;
  input_head_ = (input_head_ + 1) % inputs_.size();
  inputs_(input_head_) = inputs(0) - initial_input_;
  // du[k - nk] is the oldest value of the ring (the next to be overwritten), zero before k = nk.
  const double delayed = inputs_((input_head_ + 1) % inputs_.size());

  // A x (companion: shift up, last row -[a_n .. a_1] x) + B du[k - nk], B = a_n e_n.
  next_.head(n - 1) = state_.tail(n - 1);
  next_(n - 1) = -model_.a.reverse().dot(state_) + model_.a(n - 1) * delayed;
  // Minus the GL memory over the last min(k + 1, L) states, x[k + 1 - j] for j = 1, 2, ...
  const Eigen::Index terms =
      std::min<Eigen::Index>(sample_ + 1, memory_length_ > 0 ? memory_length_ : sample_ + 1);
  for (Eigen::Index j = 1; j <= terms; ++j) {
    next_ -= weights_(j) * history_.col((sample_ + 1 - j) % capacity);
  }
  state_ = next_;
  ++sample_;
}

}  // namespace canalid::sim
