#include "sim/lpv_arx_plant.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::sim {
namespace {

void RequireTwoInputs(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  if (inputs.size() != 2) {
    throw std::invalid_argument("LpvArxPlant: inputs has " + std::to_string(inputs.size()) +
                                " values, the plant takes 2 (u, theta)");
  }
}

double Polynomial(const core::LpvModel& model, Eigen::Index row, double theta) {
  return core::EvaluatePolynomial(model.coefficients.row(row).transpose(), theta);
}

}  // namespace

LpvArxPlant::LpvArxPlant(const core::LpvModel& model, double sample_time_s, double input_offset,
                         double output_offset, int max_delay_samples)
    : model_(model),
      sample_time_s_(sample_time_s),
      input_offset_(input_offset),
      output_offset_(output_offset) {
  if (model.kind != "first_order_arx" || model.coefficients.rows() != 3) {
    throw std::invalid_argument("LpvArxPlant: model kind '" + model.kind + "' with " +
                                std::to_string(model.coefficients.rows()) +
                                " parameters, needs first_order_arx (a1, b1, nk)");
  }
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
    throw std::invalid_argument("LpvArxPlant: sample_time_s = " + std::to_string(sample_time_s) +
                                ", must be > 0");
  }
  if (max_delay_samples < 1) {
    throw std::invalid_argument(
        "LpvArxPlant: max_delay_samples = " + std::to_string(max_delay_samples) + ", must be >= 1");
  }
  inputs_ = Eigen::VectorXd::Zero(max_delay_samples);
}

long LpvArxPlant::DelaySamples(double theta) const {
  return std::max(1L, std::lround(Polynomial(model_, 2, theta)));
}

double LpvArxPlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  return output_offset_ + Deviation(inputs);
}

double LpvArxPlant::Deviation(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireTwoInputs(inputs);
  if (sample_ == 0) return 0.0;
  const double theta = inputs(1);
  const long nk = DelaySamples(theta);
  if (nk > inputs_.size()) {
    throw std::invalid_argument(
        "LpvArxPlant: theta = " + std::to_string(theta) + " gives nk = " + std::to_string(nk) +
        " samples, beyond max_delay_samples = " + std::to_string(inputs_.size()));
  }
  // du[k - nk]: nk - 1 places behind the newest stored value du[k - 1]; zero before sample 0.
  const Eigen::Index size = inputs_.size();
  const double delayed = inputs_((head_ - (nk - 1) + size) % size);
  return -Polynomial(model_, 0, theta) * previous_ + Polynomial(model_, 1, theta) * delayed;
}

void LpvArxPlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  previous_ = Deviation(inputs);
  head_ = (head_ + 1) % inputs_.size();
  inputs_(head_) = inputs(0) - input_offset_;
  ++sample_;
}

}  // namespace canalid::sim
