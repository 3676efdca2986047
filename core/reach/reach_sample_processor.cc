#include "core/reach/reach_sample_processor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalid::core {

ReachSampleProcessor::ReachSampleProcessor(const ReachSampleProcessorOptions& options)
    : options_(options) {
  if (!(options_.sample_time_s > 0.0))
    throw std::invalid_argument("reach sample_time_s must be > 0");
  options_.online_id.sample_time_s = options_.sample_time_s;
  if (options_.online_id_enabled) {
    OnlineModelOptions id;
    id.kind = OnlineModelKind::kIntegratorDelay;
    id.sample_time_s = options_.sample_time_s;
    id.id = options_.online_id;
    online_models_.push_back(MakeOnlineModel(id));
    online_id_ = online_models_.back()->integrator_delay_bank();
  }
  std::uint32_t kinds = 0;
  for (const OnlineModelOptions& model : options_.process_models) {
    const auto bit = std::uint32_t{1} << static_cast<unsigned>(model.kind);
    if (model.kind == OnlineModelKind::kIntegratorDelay || (kinds & bit) != 0) {
      throw std::invalid_argument(
          "reach process_models: " + std::string(OnlineModelKindName(model.kind)) +
          " is not a process model kind, or is given twice");
    }
    kinds |= bit;
    online_models_.push_back(MakeOnlineModel(model));
  }
  if (options_.experiment) SetExperimentPlan(*options_.experiment);
}

ReachActions ReachSampleProcessor::Apply(const ExperimentEvent& event) {
  ReachActions actions;
  if (!options_.experiment) return actions;
  ExperimentTransition t = Step(*options_.experiment, experiment_state_, event);
  const bool starting = event.kind == ExperimentEventKind::kStart && t.actions.phase_changed;
  experiment_state_ = t.state;
  if (starting) recorded_ = 0;
  actions.write_setpoint = t.actions.write_setpoint;
  actions.restore_nominal = t.actions.restore_nominal;
  actions.experiment_phase_changed = t.actions.phase_changed;
  actions.experiment_record_complete = t.actions.start_identification;
  record_this_sample_ = t.actions.record_sample;
  return actions;
}

ReachActions ReachSampleProcessor::OnSample(const ReachSample& s) {
  ++samples_;
  last_time_s_ = s.time_s;
  // Invalid values go in as NaN: the id bank holds the integrators on the last good flows and
  // skips the regression on a bad level, the process models skip or bridge them; all count them.
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  const OnlineSample online{s.q_in_valid ? s.q_in_m3s : kNan, s.q_out_valid ? s.q_out_m3s : kNan,
                            s.level_valid ? s.level_m : kNan, s.input, s.scheduling};
  std::uint32_t updated = 0;
  for (std::size_t i = 0; i < online_models_.size(); ++i) {
    if (online_models_[i]->Update(online)) updated |= std::uint32_t{1} << i;
  }
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kSample;
  // Flows feed the record too, so the experiment needs them as much as the level.
  event.sample = {s.level_m, s.level_valid && s.q_in_valid && s.q_out_valid, s.link_ok, s.time_s};
  ReachActions actions = Apply(event);
  if (record_this_sample_) {
    // The process models start from rest: the sample before the record is its rest point.
    if (recorded_ == 0) {
      rest_input_ = previous_input_;
      rest_level_ = previous_level_;
    }
    // A tolerated invalid sample (max_invalid_samples) repeats the previous values.
    const Eigen::Index i = recorded_++;
    const bool valid = s.level_valid && s.q_in_valid && s.q_out_valid;
    record_q_in_(i) = valid || i == 0 ? s.q_in_m3s : record_q_in_(i - 1);
    record_q_out_(i) = valid || i == 0 ? s.q_out_m3s : record_q_out_(i - 1);
    record_level_(i) = valid || i == 0 ? s.level_m : record_level_(i - 1);
    // The actuator's reading may be invalid on its own: it repeats the previous one then.
    record_input_(i) = std::isfinite(s.input) || i == 0 ? s.input : record_input_(i - 1);
  }
  if (std::isfinite(s.input)) previous_input_ = s.input;
  if (s.level_valid) previous_level_ = s.level_m;
  actions.online_updated = updated != 0;
  actions.online_models_updated = updated;
  return actions;
}

ReachActions ReachSampleProcessor::StartExperiment() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kStart;
  event.sample.time_s = last_time_s_;
  return Apply(event);
}

ReachActions ReachSampleProcessor::StopExperiment() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kStop;
  return Apply(event);
}

ReachActions ReachSampleProcessor::StopJointExperiment() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kJointStop;
  return Apply(event);
}

ReachActions ReachSampleProcessor::EndJointExperiment() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kJointEnd;
  return Apply(event);
}

ReachActions ReachSampleProcessor::OnLinkLost() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kSample;
  event.sample.link_ok = false;
  return Apply(event);
}

ReachActions ReachSampleProcessor::OnWriteFailed() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kWriteFailed;
  return Apply(event);
}

ReachActions ReachSampleProcessor::OnGuardNotPersisted() {
  ExperimentEvent event;
  event.kind = ExperimentEventKind::kGuardNotPersisted;
  return Apply(event);
}

void ReachSampleProcessor::ResetOnlineEstimator() {
  for (const auto& model : online_models_) model->Reset();
}

bool ReachSampleProcessor::SetExperimentPlan(const ExperimentPlan& plan) {
  const ExperimentPhase phase = experiment_state_.phase;
  if (IsRunning(phase) || phase == ExperimentPhase::kIdentifying) return false;
  plan.Validate();
  options_.experiment = plan;
  const auto n = static_cast<Eigen::Index>(plan.excite_samples);
  record_q_in_.resize(n);
  record_q_out_.resize(n);
  record_level_.resize(n);
  record_input_.resize(n);
  recorded_ = 0;
  return true;
}

std::optional<IntegratorDelayIdentification> ReachSampleProcessor::IdentifyRecord(
    ReachActions* actions) {
  ExperimentEvent event;
  std::optional<IntegratorDelayIdentification> result;
  identification_problem_.clear();
  if (options_.batch_id) {
    try {
      result = IdentifyIntegratorDelay(record_q_in_.head(recorded_), record_q_out_.head(recorded_),
                                       record_level_.head(recorded_), options_.sample_time_s,
                                       options_.batch);
      const IntegratorDelayModel& m = result->fit.model;
      identification_problem_ = IntegratorDelayBoundsProblem(m.area_m2(), m.nk, options_.online_id);
      if (!std::isfinite(m.b)) identification_problem_ = "b is not finite";
    } catch (const std::invalid_argument& e) {
      result.reset();
      identification_problem_ = e.what();
    }
  }
  idz_result_.reset();
  idz_problem_.clear();
  if (options_.batch_idz) {
    try {
      idz_result_ =
          IdentifyIdz(record_q_in_.head(recorded_), record_q_out_.head(recorded_),
                      record_level_.head(recorded_), options_.sample_time_s, *options_.batch_idz);
      const IdzFit& fit = idz_result_->fit;
      idz_problem_ = IntegratorDelayBoundsProblem(fit.area_m2, fit.nk, options_.online_id);
      if (!std::isfinite(fit.area_m2)) idz_problem_ = "the area is not finite";
    } catch (const std::invalid_argument& e) {
      idz_result_.reset();
      idz_problem_ = e.what();
    }
  }
  process_results_.clear();
  ProcessBatchOptions batch = options_.batch_process;
  batch.max_delay_s = options_.online_id.max_delay_samples * options_.sample_time_s;
  batch.min_delay_samples = std::max(options_.online_id.min_delay_samples, 1);
  bool process_ok = false;
  // The record with its rest point (the sample before it, at the nominal setpoint) first: the
  // fits take the first sample as the state of rest the input moves from.
  Eigen::VectorXd input(recorded_ + 1), level(recorded_ + 1);
  input << rest_input_, record_input_.head(recorded_);
  level << rest_level_, record_level_.head(recorded_);
  for (const ProcessBatchKind kind : options_.batch_process_models) {
    if (!input.allFinite() || !level.allFinite()) {
      ProcessBatchResult none;
      none.kind = kind;
      none.problem = !input.allFinite()
                         ? "no valid actuator reading before or at the start of the record"
                         : "no valid level before or at the start of the record";
      process_results_.push_back(none);
      continue;
    }
    process_results_.push_back(FitProcessBatch(kind, input, level, options_.sample_time_s, batch));
    process_ok = process_ok || process_results_.back().ok();
  }
  const bool idz_ok = idz_result_.has_value() && idz_problem_.empty();
  const bool nothing_to_identify =
      !options_.batch_id && !options_.batch_idz && options_.batch_process_models.empty();
  if (!options_.batch_id && !process_ok && !idz_ok && !nothing_to_identify) {
    identification_problem_ =
        options_.batch_idz ? "idz: " + idz_problem_ : process_results_.front().problem;
  }
  event.kind = identification_problem_.empty() ? ExperimentEventKind::kIdentificationSucceeded
                                               : ExperimentEventKind::kIdentificationFailed;
  const ReachActions done = Apply(event);
  if (actions != nullptr) *actions = done;
  return result;
}

}  // namespace canalid::core
