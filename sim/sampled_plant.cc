#include "sim/sampled_plant.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace canalid::sim {
namespace {

void RequireInputs(const Eigen::Ref<const Eigen::VectorXd>& inputs, int count) {
  if (inputs.size() != count) {
    throw std::invalid_argument("SampledPlant: inputs has " + std::to_string(inputs.size()) +
                                " values, the plant takes " + std::to_string(count));
  }
}

}  // namespace

FractionalFoptdPlant::FractionalFoptdPlant(const core::FractionalFoptdParams& params,
                                           const core::OustaloupOptions& band, double sample_time_s,
                                           double input_offset, double output_offset,
                                           double initial_input)
    : simulator_(params, sample_time_s, band),
      sample_time_s_(sample_time_s),
      initial_input_(initial_input),
      level_(output_offset + params.gain * (initial_input - input_offset)) {}

double FractionalFoptdPlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireInputs(inputs, 1);
  return level_ + simulator_.output();
}

void FractionalFoptdPlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  RequireInputs(inputs, 1);
  simulator_.Advance(inputs(0) - initial_input_);
}

IntegratorDelayLevelPlant::IntegratorDelayLevelPlant(const core::IntegratorDelayModel& model,
                                                     double p21_s_per_m2, double offset_m,
                                                     double drift_m_per_sample, int fit_from_sample,
                                                     double initial_inflow_m3s, double p22_s_per_m2)
    : model_(model),
      p21_(p21_s_per_m2),
      p22_(p22_s_per_m2),
      offset_m_(offset_m),
      drift_m_per_sample_(drift_m_per_sample),
      k0_(fit_from_sample),
      previous_outflow_m3s_(initial_inflow_m3s) {
  if (model.nk < 0) {
    throw std::invalid_argument("IntegratorDelayLevelPlant: nk = " + std::to_string(model.nk) +
                                ", must be >= 0");
  }
  if (!(model.sample_time_s > 0.0) || !std::isfinite(model.b)) {
    throw std::invalid_argument(
        "IntegratorDelayLevelPlant: sample_time_s = " + std::to_string(model.sample_time_s) +
        " (must be > 0), b = " + std::to_string(model.b) + " (must be finite)");
  }
  if (fit_from_sample < 0) {
    throw std::invalid_argument("IntegratorDelayLevelPlant: fit_from_sample = " +
                                std::to_string(fit_from_sample) + ", must be >= 0");
  }
  inflow_history_ = Eigen::VectorXd::Constant(model.nk, initial_inflow_m3s);
}

double IntegratorDelayLevelPlant::DelayedInflow(double inflow_now) const {
  return model_.nk == 0 ? inflow_now : inflow_history_(head_);
}

double IntegratorDelayLevelPlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireInputs(inputs, 2);
  const double delayed = DelayedInflow(inputs(0));
  const double integrated =
      sample_ >= k0_ ? integrated_m3s_ + delayed - previous_outflow_m3s_ : 0.0;
  return model_.b * integrated + p21_ * delayed - p22_ * inputs(1) + offset_m_ +
         drift_m_per_sample_ * static_cast<double>(sample_ - k0_);
}

void IntegratorDelayLevelPlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  RequireInputs(inputs, 2);
  const double delayed = DelayedInflow(inputs(0));
  if (sample_ >= k0_) integrated_m3s_ += delayed - previous_outflow_m3s_;
  if (model_.nk > 0) {
    // q_in(k - nk) leaves the ring and q_in(k) takes its place: the oldest is next.
    inflow_history_(head_) = inputs(0);
    head_ = (head_ + 1) % model_.nk;
  }
  previous_outflow_m3s_ = inputs(1);
  ++sample_;
}

ArxPlant::ArxPlant(const core::ArxModel& model, double sample_time_s,
                   const Eigen::Ref<const Eigen::VectorXd>& initial_outputs)
    : model_(model), sample_time_s_(sample_time_s), initial_outputs_(initial_outputs) {
  if (!(sample_time_s > 0.0)) {
    throw std::invalid_argument("ArxPlant: sample_time_s = " + std::to_string(sample_time_s) +
                                ", must be > 0");
  }
  const std::size_t inputs = model.b.size();
  if (model.a.size() != model.orders.na || model.orders.nk.size() != inputs || inputs == 0) {
    throw std::invalid_argument("ArxPlant: a has " + std::to_string(model.a.size()) +
                                " coefficients for na = " + std::to_string(model.orders.na) +
                                ", b has " + std::to_string(inputs) + " inputs and nk " +
                                std::to_string(model.orders.nk.size()) +
                                " (need equal, at least one input)");
  }
  Eigen::Index lags = 1;
  for (std::size_t i = 0; i < inputs; ++i) {
    if (model.orders.nk[i] < 0) {
      throw std::invalid_argument("ArxPlant: nk[" + std::to_string(i) +
                                  "] = " + std::to_string(model.orders.nk[i]) + ", must be >= 0");
    }
    lags = std::max<Eigen::Index>(lags, model.orders.nk[i] + model.b[i].size());
  }
  input_ring_ = Eigen::MatrixXd::Zero(lags, static_cast<Eigen::Index>(inputs));
  output_ring_ = Eigen::VectorXd::Zero(std::max(model.orders.na, 1));
}

double ArxPlant::Output(const Eigen::Ref<const Eigen::VectorXd>& inputs) const {
  RequireInputs(inputs, input_count());
  if (sample_ < initial_outputs_.size()) return initial_outputs_(sample_);
  const Eigen::Index lags = input_ring_.rows();
  double value = 0.0;
  for (Eigen::Index i = 0; i < inputs.size(); ++i) {
    const Eigen::VectorXd& b = model_.b[static_cast<std::size_t>(i)];
    const Eigen::Index nk = model_.orders.nk[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < b.size(); ++j) {
      const Eigen::Index m = nk + j;  // u_i(t - m)
      if (m > sample_) continue;      // before sample 0: zero
      value += b(j) * (m == 0 ? inputs(i) : input_ring_((input_head_ - m + lags) % lags, i));
    }
  }
  const Eigen::Index na = output_ring_.size();
  for (Eigen::Index j = 1; j <= model_.a.size() && j <= sample_; ++j) {
    value -= model_.a(j - 1) * output_ring_((output_head_ - j + na) % na);
  }
  return value;
}

void ArxPlant::Advance(const Eigen::Ref<const Eigen::VectorXd>& inputs) {
  const double y = Output(inputs);
  output_ring_(output_head_) = y;
  output_head_ = (output_head_ + 1) % output_ring_.size();
  input_ring_.row(input_head_) = inputs.transpose();
  input_head_ = (input_head_ + 1) % input_ring_.rows();
  ++sample_;
}

SampledPoolPlant::SampledPoolPlant(std::unique_ptr<SampledPlant> plant, double inflow_m3s,
                                   double outflow_m3s)
    : plant_(std::move(plant)) {
  if (!plant_ || (plant_->input_count() != 1 && plant_->input_count() != 2)) {
    throw std::invalid_argument(
        "SampledPoolPlant: needs a plant with 1 or 2 inputs (got " +
        std::string(plant_ ? std::to_string(plant_->input_count()) : std::string("none")) + ")");
  }
  inputs_.resize(plant_->input_count());
  SetFlows(inflow_m3s, outflow_m3s);
}

void SampledPoolPlant::SetFlows(double inflow_m3s, double outflow_m3s) {
  inputs_(0) = inflow_m3s;
  if (inputs_.size() == 2) inputs_(1) = outflow_m3s;
}

void SampledPoolPlant::Step(double dt_s) {
  const double ts = plant_->sample_time_s();
  const double samples = std::round(dt_s / ts);
  if (!(dt_s > 0.0) || samples < 1.0 || std::abs(samples * ts - dt_s) > 1e-9 * dt_s) {
    throw std::invalid_argument("SampledPoolPlant::Step: dt_s = " + std::to_string(dt_s) +
                                ", must be a positive whole multiple of the sample time " +
                                std::to_string(ts) + " s");
  }
  for (long i = 0; i < static_cast<long>(samples); ++i) plant_->Advance(inputs_);
  samples_ += static_cast<long>(samples);
}

}  // namespace canalid::sim
