#include "daemon/config/plan_from_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/experiment/experiment_design.h"

namespace canalid::config {
using namespace canalid::core;  // NOLINT(google-build-using-namespace): the maths the schema uses

ExperimentDesign DesignExperiment(const DaemonConfig& config, const ExperimentConfig& experiment) {
  const ReachConfig* reach = config.FindReach(experiment.reach);
  if (experiment.mode != ExperimentMode::kDesign || reach == nullptr) {
    throw std::invalid_argument("experiment \"" + experiment.name +
                                "\": not a design-mode experiment of a known reach");
  }
  ExperimentDesignRequest request;
  request.nominal_flow_m3s = reach->nominal_inflow_m3s;
  request.expected_delay_s = reach->expected_delay_s;
  request.sample_time_s = ReachSampleTimeS(config, *reach);
  request.amplitude_percent = experiment.amplitude_percent;
  request.duration_factor = experiment.duration_factor;
  return DesignPrbsExperiment(request);
}

ExperimentPlan BuildExperimentPlan(const DaemonConfig& config, const ExperimentConfig& experiment,
                                   double nominal_setpoint) {
  const std::string where = "experiment \"" + experiment.name + "\": ";
  const ReachConfig* reach = config.FindReach(experiment.reach);
  if (reach == nullptr) throw std::invalid_argument(where + "unknown reach " + experiment.reach);
  const ChannelConfig* actuator = config.FindChannel(reach->actuator);
  if (actuator == nullptr)
    throw std::invalid_argument(where + "unknown actuator " + reach->actuator);
  const double ts = ReachSampleTimeS(config, *reach);

  ExperimentPlan plan;
  const bool step_mode = experiment.mode == ExperimentMode::kStep;
  plan.prbs.nominal = nominal_setpoint;
  plan.prbs.seed = static_cast<std::uint32_t>(experiment.seed);
  if (experiment.mode == ExperimentMode::kDesign) {
    const ExperimentDesign design = DesignExperiment(config, experiment);
    plan.prbs.amplitude = reach->actuator_gain_m3s_per_unit
                              ? design.amplitude_m3s / std::abs(*reach->actuator_gain_m3s_per_unit)
                              : experiment.amplitude_percent / 100.0 * std::abs(nominal_setpoint);
    plan.prbs.clock_period_samples = design.clock_period_samples;
    plan.prbs.order = design.order;
    plan.excite_samples = design.num_samples;
  } else if (experiment.mode == ExperimentMode::kStep) {
    // Up by the amplitude, hold, back to nominal, hold; the PRBS fields stay valid but unused.
    plan.prbs.amplitude = experiment.amplitude;
    plan.step_hold_samples = std::llround(experiment.hold_s / ts);
    plan.excite_samples = 2 * plan.step_hold_samples;
  } else {
    plan.prbs.amplitude = experiment.amplitude;
    plan.prbs.clock_period_samples = static_cast<int>(std::lround(experiment.clock_period_s / ts));
    plan.prbs.order = experiment.order;
    plan.excite_samples = static_cast<std::int64_t>(experiment.periods) *
                          ((std::int64_t{1} << experiment.order) - 1) *
                          plan.prbs.clock_period_samples;
  }
  // The LFSR's start state is the seed's low `order` bits (the validator checks they are not all
  // zero): a seed written for a longer register still starts a shorter one.
  if (!step_mode) {
    plan.prbs.seed &= static_cast<std::uint32_t>((std::uint64_t{1} << plan.prbs.order) - 1);
  }
  if (!(plan.prbs.amplitude > 0.0)) {
    throw std::invalid_argument(where + "amplitude " + std::to_string(plan.prbs.amplitude) +
                                " (actuator units) must be > 0 (nominal setpoint " +
                                std::to_string(nominal_setpoint) + ")");
  }
  // A step covers [nominal, nominal + amplitude], a PRBS nominal +- amplitude.
  const bool step = plan.step_hold_samples > 0;
  const double low = step ? nominal_setpoint : nominal_setpoint - plan.prbs.amplitude;
  const double high = nominal_setpoint + plan.prbs.amplitude;
  if (!(low >= actuator->setpoint_min && high <= actuator->setpoint_max)) {
    throw std::invalid_argument(where + "nominal " + std::to_string(nominal_setpoint) +
                                (step ? " + step " : " +- ") + std::to_string(plan.prbs.amplitude) +
                                " leaves the actuator's [" +
                                std::to_string(actuator->setpoint_min) + ", " +
                                std::to_string(actuator->setpoint_max) + "]");
  }
  // The small tolerance keeps settle_s = n Ts at n samples despite rounding in the division.
  plan.settle_samples = static_cast<std::int64_t>(std::ceil(experiment.settle_s / ts - 1e-9));
  plan.level_min_m = reach->level_min_m;
  plan.level_max_m = reach->level_max_m;
  plan.max_invalid_samples = experiment.max_invalid_samples;
  // Samples carry the poll's wall time: the bound is in wall seconds (Ts / time_scale).
  plan.max_sample_gap_s = experiment.max_sample_gap_periods * ts / config.daemon.time_scale;
  plan.Validate();
  return plan;
}

core::OnlineModelSettings BuildOnlineModelSettings(const DaemonConfig& config,
                                                   const ReachConfig& reach) {
  core::OnlineModelSettings settings;
  settings.sample_time_s = ReachSampleTimeS(config, reach);
  settings.rls_method = reach.rls_method;
  settings.forgetting = reach.forgetting;
  settings.initial_covariance = reach.initial_covariance;
  settings.min_delay_s = reach.min_delay_s;
  settings.max_delay_s = reach.max_delay_s;
  settings.arx_na = reach.arx_na;
  settings.arx_nb = reach.arx_nb;
  settings.fractional_alphas = reach.fractional_alphas;
  settings.fractional_delay_s = reach.fractional_delay_s;
  settings.lpv_na = reach.lpv_na;
  settings.lpv_nb = reach.lpv_nb;
  settings.lpv_delay_s = reach.lpv_delay_s;
  settings.frac_ss_q = reach.frac_ss_q;
  settings.frac_ss_delay_s = reach.frac_ss_delay_s;
  settings.idz_p22_s_per_m2 = reach.idz_p22_s_per_m2.value_or(0.0);
  settings.wave_front_term = reach.id_wave_front.value_or(true);
  return settings;
}

OnlineIntegratorDelayOptions BuildOnlineIntegratorDelayOptions(const DaemonConfig& config,
                                                               const ReachConfig& reach) {
  return core::OnlineModelOptionsFor(core::OnlineModelKind::kIntegratorDelay,
                                     BuildOnlineModelSettings(config, reach))
      .id;
}

ReachControllerOptions BuildReachControllerOptions(
    const std::shared_ptr<const DaemonConfig>& config, const ReachConfig& reach,
    const std::function<int(const std::string& channel)>& channel_index) {
  ReachControllerOptions options;
  options.name = reach.name;
  options.channels.q_in = channel_index(reach.inflow);
  options.channels.q_out = channel_index(reach.outflow);
  options.channels.level = channel_index(reach.level);
  options.channels.actuator = channel_index(reach.actuator);
  ReachSampleProcessorOptions& pipeline = options.pipeline;
  pipeline.sample_time_s = ReachSampleTimeS(*config, reach);
  if (!reach.actuator_position.empty())
    options.channels.actuator_position = channel_index(reach.actuator_position);
  if (!reach.lpv_scheduling.empty())
    options.channels.scheduling = channel_index(reach.lpv_scheduling);
  const core::OnlineModelSettings settings = BuildOnlineModelSettings(*config, reach);
  pipeline.online_id_enabled = false;
  for (const OnlineModel kind : reach.online_models) {
    if (kind == OnlineModel::kIntegratorDelay) {
      pipeline.online_id_enabled = true;
    } else {
      pipeline.process_models.push_back(core::OnlineModelOptionsFor(kind, settings));
    }
  }
  pipeline.online_id =
      core::OnlineModelOptionsFor(core::OnlineModelKind::kIntegratorDelay, settings).id;
  pipeline.batch_id = false;
  for (const BatchModel model : reach.batch_models) {
    switch (model) {
      case BatchModel::kId:
        pipeline.batch_id = true;
        break;
      case BatchModel::kIdz: {
        core::IdzIdentificationOptions idz;
        if (reach.idz_p22_s_per_m2) {
          idz.fit.p22_prior_s_per_m2 = *reach.idz_p22_s_per_m2;
          idz.fit.p22_prior_std_s_per_m2 = reach.idz_p22_std_s_per_m2.value_or(
              core::kIdzPriorRelativeStd * *reach.idz_p22_s_per_m2);
        }
        pipeline.batch_idz = idz;
        break;
      }
      case BatchModel::kFoptd:
        pipeline.batch_process_models.push_back(core::ProcessBatchKind::kFoptd);
        break;
      case BatchModel::kFracFoptd:
        pipeline.batch_process_models.push_back(core::ProcessBatchKind::kFractionalFoptd);
        break;
      case BatchModel::kSoptd:
        pipeline.batch_process_models.push_back(core::ProcessBatchKind::kSoptd);
        break;
      case BatchModel::kArx:
        pipeline.batch_process_models.push_back(core::ProcessBatchKind::kArx);
        break;
      case BatchModel::kFracSs:
        pipeline.batch_process_models.push_back(core::ProcessBatchKind::kFracSs);
        break;
    }
  }
  pipeline.batch_process.arx_na = reach.arx_na;
  pipeline.batch_process.arx_nb = reach.arx_nb;
  pipeline.batch_process.frac_ss_q = reach.frac_ss_q;
  pipeline.batch.fit.min_nk = pipeline.online_id.min_delay_samples;
  pipeline.batch.fit.max_nk = pipeline.online_id.max_delay_samples;
  pipeline.batch.fit.closed_loop = reach.closed_loop;
  if (pipeline.batch_idz) {
    pipeline.batch_idz->fit.min_nk = pipeline.batch.fit.min_nk;
    pipeline.batch_idz->fit.max_nk = pipeline.batch.fit.max_nk;
  }
  options.nominal_setpoint = reach.nominal_setpoint;
  for (const ExperimentConfig& experiment : config->experiments) {
    if (experiment.reach != reach.name) continue;
    core::ReachExperiment& e = options.experiments.emplace_back();
    e.name = experiment.name;
    e.start_on_start = experiment.start == ExperimentStart::kOnStart;
    e.plan_for_nominal = [config, name = experiment.name](double nominal) {
      return BuildExperimentPlan(*config, *config->FindExperiment(name), nominal);
    };
  }
  return options;
}

std::vector<core::JointExperiment> BuildJointExperiments(
    const DaemonConfig& config, const std::vector<std::string>& reach_names) {
  auto index = [&](const std::string& reach) -> std::optional<std::size_t> {
    const auto at = std::find(reach_names.begin(), reach_names.end(), reach);
    if (at == reach_names.end()) return std::nullopt;
    return static_cast<std::size_t>(at - reach_names.begin());
  };
  std::vector<core::JointExperiment> joints;
  for (const ExperimentConfig& experiment : config.experiments) {
    const std::optional<std::size_t> leader = index(experiment.reach);
    if (experiment.with.empty() || !leader) continue;
    core::JointExperiment& joint = joints.emplace_back();
    joint.leader = {*leader, experiment.name};
    for (const std::string& name : experiment.with) {
      const ExperimentConfig* partner = config.FindExperiment(name);
      if (partner == nullptr) continue;
      if (const std::optional<std::size_t> reach = index(partner->reach)) {
        joint.partners.push_back({*reach, partner->name});
      }
    }
  }
  return joints;
}

}  // namespace canalid::config
