#include "daemon/canalidd/lcm_publisher.h"

#include <cmath>
#include <limits>
#include <vector>

#include "drivers/json/model_json_params.h"

namespace canalid::daemon {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// core's flag bits are the message's.
static_assert(core::kFlagNan == canalid::model_snapshot_t::FLAG_NAN);
static_assert(core::kFlagWindup == canalid::model_snapshot_t::FLAG_WINDUP);
static_assert(core::kFlagLowExcitation == canalid::model_snapshot_t::FLAG_LOW_EXCITATION);
static_assert(core::kFlagIllConditioned == canalid::model_snapshot_t::FLAG_ILL_CONDITIONED);
static_assert(core::kFlagFrozen == canalid::model_snapshot_t::FLAG_FROZEN);
static_assert(core::kFlagOutOfBounds == canalid::model_snapshot_t::FLAG_OUT_OF_BOUNDS);

}  // namespace

int8_t ExperimentStateCode(core::ExperimentPhase phase) {
  switch (phase) {
    case core::ExperimentPhase::kIdle:
      return canalid::experiment_state_t::STATE_IDLE;
    case core::ExperimentPhase::kSettling:
      return canalid::experiment_state_t::STATE_SETTLING;
    case core::ExperimentPhase::kExciting:
      return canalid::experiment_state_t::STATE_EXCITING;
    case core::ExperimentPhase::kIdentifying:
      return canalid::experiment_state_t::STATE_RECOVERING;
    case core::ExperimentPhase::kDone:
      return canalid::experiment_state_t::STATE_DONE;
    case core::ExperimentPhase::kAborted:
      return canalid::experiment_state_t::STATE_ABORTED;
  }
  return canalid::experiment_state_t::STATE_IDLE;
}

namespace {

// num_params = n; the arrays only ever grow (LCM encodes num_params entries), so that the names'
// strings keep their storage when kinds with fewer parameters are published in between.
void SetParamCount(canalid::model_snapshot_t& m, std::size_t n) {
  m.num_params = static_cast<int32_t>(n);
  if (m.param_names.size() < n) {
    m.param_names.resize(n);
    m.param_values.resize(n);
    m.param_std_devs.resize(n);
  }
}

void SetParams(canalid::model_snapshot_t& m,
               std::initializer_list<std::pair<const char*, std::pair<double, double>>> p) {
  SetParamCount(m, p.size());
  std::size_t i = 0;
  for (const auto& [name, value] : p) {
    if (m.param_names[i] != name) m.param_names[i] = name;
    m.param_values[i] = value.first;
    m.param_std_devs[i] = value.second;
    ++i;
  }
}

}  // namespace

LcmPublisher::LcmPublisher(drivers::Bus& bus, std::string prefix)
    : bus_(bus), prefix_(std::move(prefix)) {}

const std::string& LcmPublisher::Channel(std::map<std::string, std::string, std::less<>>& cache,
                                         const char* kind, const std::string& name) {
  // Built once per name: the per-sample path does not allocate channel names.
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, prefix_ + kind + name).first;
  return it->second;
}

template <class Message>
void LcmPublisher::Send(const std::string& channel, const Message& message) {
  if (!drivers::PublishMessage(bus_, channel, message, buffer_)) ++failures_;
}

void LcmPublisher::PublishSample(const std::string& plc,
                                 const std::vector<std::string>& channel_names,
                                 const drivers::PollSample& s) {
  sample_.utime = ToUtime(s.time_s);
  sample_.sequence = s.sequence;
  if (sample_.source != plc) sample_.source = plc;
  sample_.status = static_cast<int32_t>(s.status.kind);
  sample_.exception_code =
      s.status.kind == drivers::PlcErrorKind::kException ? s.status.exception_code : 0;
  sample_.round_trip_s = static_cast<float>(s.round_trip_s);
  sample_.num_channels = static_cast<int32_t>(channel_names.size());
  if (sample_.channel_names != channel_names) sample_.channel_names = channel_names;
  sample_.values.assign(s.values.begin(), s.values.end());
  sample_.quality.resize(s.quality.size());
  for (std::size_t i = 0; i < s.quality.size(); ++i)
    sample_.quality[i] = static_cast<int8_t>(s.quality[i]);
  Send(Channel(sample_channels_, "SAMPLE_", plc), sample_);
}

void LcmPublisher::PublishOnlineModel(const std::string& reach,
                                      const core::OnlineModelSnapshot& snapshot, double time_s,
                                      std::string_view estimator) {
  model_.utime = ToUtime(time_s);
  model_.reach = reach;
  model_.model_kind = core::OnlineModelKindName(snapshot.kind);
  model_.estimator = estimator.empty() ? snapshot.estimator : estimator;
  model_.samples_used = snapshot.samples_used;
  const auto n = static_cast<std::size_t>(snapshot.num_params);
  SetParamCount(model_, n);
  for (std::size_t i = 0; i < n; ++i) {
    // Assigned only when different: the strings keep their storage from one message to the next.
    if (model_.param_names[i] != snapshot.names[i]) model_.param_names[i] = snapshot.names[i];
    model_.param_values[i] = snapshot.values[i];
    model_.param_std_devs[i] = snapshot.std_devs[i];
  }
  model_.trace_p = snapshot.trace_p;
  model_.condition_number = snapshot.condition_number;
  model_.excitation = snapshot.excitation;
  model_.prediction_error_rms = snapshot.prediction_error_rms;
  model_.flags = snapshot.flags;
  SendModel(reach);
}

void LcmPublisher::SendModel(const std::string& reach) {
  Send(Channel(model_channels_, "MODEL_", reach), model_);
  if (model_observer_) model_observer_(model_);
}

void LcmPublisher::PublishBatchId(const std::string& reach,
                                  const core::IntegratorDelayIdentification& result, double time_s,
                                  std::int64_t samples, bool out_of_bounds) {
  const core::IntegratorDelayFit& fit = result.fit;
  model_.utime = ToUtime(time_s);
  model_.reach = reach;
  model_.model_kind = "id";
  model_.estimator = "batch";
  model_.samples_used = samples;
  SetParams(model_, {{"delay_s", {fit.model.delay_s(), kNan}},
                     {"area_m2", {fit.model.area_m2(), kNan}},
                     {"b", {fit.model.b, kNan}},
                     {"p21_s_per_m2", {fit.wave_front_gain_s_per_m2, kNan}},
                     {"offset_m", {fit.offset_m, kNan}},
                     {"fit_percent", {fit.metrics.fit_percent, kNan}}});
  model_.trace_p = kNan;
  model_.condition_number = kNan;
  model_.excitation = kNan;
  model_.prediction_error_rms = fit.metrics.rmse;
  model_.flags = (std::isfinite(fit.model.b) ? 0 : core::kFlagNan) |
                 (out_of_bounds ? core::kFlagOutOfBounds : 0);
  SendModel(reach);
}

void LcmPublisher::PublishModelJson(const std::string& reach, const nlohmann::json& model,
                                    double time_s, const char* estimator, std::int64_t samples,
                                    std::int32_t flags) {
  model_.utime = ToUtime(time_s);
  model_.reach = reach;
  model_.model_kind = model.value("model", std::string("unknown"));
  model_.estimator = estimator;
  model_.samples_used = samples;
  const std::vector<drivers::ModelJsonParam> params = drivers::ModelJsonParams(model);
  SetParamCount(model_, params.size());
  for (std::size_t i = 0; i < params.size(); ++i) {
    model_.param_names[i] = params[i].name;
    model_.param_values[i] = params[i].value;
    model_.param_std_devs[i] = params[i].std_dev;
  }
  model_.trace_p = kNan;
  model_.condition_number = kNan;
  model_.excitation = kNan;
  const nlohmann::json* metrics = model.contains("metrics") ? &model["metrics"] : nullptr;
  model_.prediction_error_rms =
      metrics != nullptr && metrics->contains("rmse") && (*metrics)["rmse"].is_number()
          ? (*metrics)["rmse"].get<double>()
          : kNan;
  model_.flags = flags;
  SendModel(reach);
}

void LcmPublisher::PublishExperiment(const std::string& reach, const std::string& experiment,
                                     const core::ExperimentState& state,
                                     const core::ExperimentPlan& plan, const std::string& actuator,
                                     double time_s) {
  experiment_.utime = ToUtime(time_s);
  experiment_.reach = reach;
  experiment_.experiment = experiment;
  experiment_.state = ExperimentStateCode(state.phase);
  const bool exciting = state.phase == core::ExperimentPhase::kExciting;
  experiment_.step = exciting ? static_cast<int32_t>(state.samples_in_phase) : 0;
  experiment_.num_steps = static_cast<int32_t>(plan.excite_samples);
  experiment_.setpoint_channel = actuator;
  experiment_.setpoint = state.setpoint;
  experiment_.reason = core::PhaseReasonText(plan, state);
  Send(Channel(experiment_channels_, "EXPERIMENT_", reach), experiment_);
}

void LcmPublisher::PublishRestart(const std::string& reach, const std::string& actuator,
                                  double setpoint, const std::string& reason, double time_s) {
  experiment_.utime = ToUtime(time_s);
  experiment_.reach = reach;
  experiment_.experiment.clear();  // the interrupted run's experiment is in its guard
  experiment_.state = canalid::experiment_state_t::STATE_ABORTED;
  experiment_.step = 0;
  experiment_.num_steps = 0;
  experiment_.setpoint_channel = actuator;
  experiment_.setpoint = setpoint;
  experiment_.reason = reason;
  Send(Channel(experiment_channels_, "EXPERIMENT_", reach), experiment_);
}

void LcmPublisher::PublishHealth(const HealthReport& report, double uptime_s, double time_s) {
  health_.utime = ToUtime(time_s);
  health_.component = report.component;
  health_.uptime_s = uptime_s;
  health_.num_counters = static_cast<int32_t>(report.counters.size());
  health_.counter_names.resize(report.counters.size());
  health_.counter_values.resize(report.counters.size());
  for (std::size_t i = 0; i < report.counters.size(); ++i) {
    health_.counter_names[i] = report.counters[i].first;
    health_.counter_values[i] = report.counters[i].second;
  }
  health_.num_gauges = static_cast<int32_t>(report.gauges.size());
  health_.gauge_names.resize(report.gauges.size());
  health_.gauge_values.resize(report.gauges.size());
  for (std::size_t i = 0; i < report.gauges.size(); ++i) {
    health_.gauge_names[i] = report.gauges[i].first;
    health_.gauge_values[i] = report.gauges[i].second;
  }
  Send(prefix_ + "HEALTH", health_);
}

void LcmPublisher::PublishConfig(const std::string& path, const std::string& text, double time_s) {
  canalid::config_t message;
  message.utime = ToUtime(time_s);
  message.path = path;
  message.version = "0.1.0";
  message.text = text;
  Send(prefix_ + "CONFIG", message);
}

}  // namespace canalid::daemon
