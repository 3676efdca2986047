#include "sim/soptd_plant.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::sim {
namespace {

core::DelayedZoh<2> Cascade(const core::SoptdModel& model, double sample_time_s) {
  const double t1 = model.time_constants_s[0];
  const double t2 = model.time_constants_s[1];
  for (const double t : {t1, t2}) {
    if (!(t > 0.0) || !std::isfinite(t)) {
      throw std::invalid_argument("SoptdPlant: time_constants_s = (" + std::to_string(t1) + ", " +
                                  std::to_string(t2) + "), both must be > 0 and finite");
    }
  }
  if (!std::isfinite(model.gain)) {
    throw std::invalid_argument("SoptdPlant: gain = " + std::to_string(model.gain) +
                                ", must be finite");
  }
  Eigen::Matrix2d a;
  a << -1.0 / t1, 0.0, 1.0 / t2, -1.0 / t2;
  return core::DelayedZoh<2>(a, Eigen::Vector2d(model.gain / t1, 0.0), Eigen::RowVector2d(0.0, 1.0),
                             sample_time_s, model.delay_s);
}

void RequireOneInput(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  if (inputs.size() != 1) {
    throw std::invalid_argument("SoptdPlant: inputs has " + std::to_string(inputs.size()) +
                                " values, the plant takes 1");
  }
}

}  // namespace

SoptdPlant::SoptdPlant(const core::SoptdModel& model, double sample_time_s, double input_offset,
                       double output_offset, double initial_input)
    : system_(Cascade(model, sample_time_s)),
      sample_time_s_(sample_time_s),
      initial_input_(initial_input),
      level_(output_offset + model.gain * (initial_input - input_offset)),
      ring_(Eigen::VectorXd::Zero(system_.whole_delay() + 2)) {}

double SoptdPlant::Past(int age) const {
  const Eigen::Index size = ring_.size();
  return ring_((head_ - age + size) % size);
}

double SoptdPlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireOneInput(inputs);
  return level_ + system_.Output(state_);
}

void SoptdPlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  RequireOneInput(inputs);
  head_ = (head_ + 1) % ring_.size();
  ring_(head_) = inputs(0) - initial_input_;
  // Over [k Ts, (k+1) Ts) the delayed input is u[k-d-1] for the first f Ts, then u[k-d].
  const int d = system_.whole_delay();
  state_ = system_.Next(state_, Past(d + 1), Past(d));
}

}  // namespace canalid::sim
