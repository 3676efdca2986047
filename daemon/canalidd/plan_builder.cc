#include "daemon/canalidd/plan_builder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/experiment_design.h"
#include "daemon/canalidd/driver_config.h"

namespace canalid::daemon {
namespace {

int ChannelIndex(const drivers::PollerConfig& poller, const std::string& name) {
  for (std::size_t i = 0; i < poller.channels.size(); ++i) {
    if (poller.channels[i].name == name) return static_cast<int>(i);
  }
  throw std::invalid_argument("channel '" + name + "' is not polled on PLC '" + poller.plc_name + "'");
}

int Samples(double seconds, double sample_time_s) {
  return static_cast<int>(std::lround(seconds / sample_time_s));
}

// The experiment of a reach in samples; the amplitude is in actuator units, or a fraction of the
// nominal setpoint when that is only known at run time.
void PlanExperiment(const core::ReachConfig& reach,
                    const core::ExperimentConfig& experiment, double ts, ReachWiring& wiring) {
  core::ExperimentPlan plan;
  plan.prbs.seed = static_cast<std::uint32_t>(experiment.seed);
  plan.settle_samples = Samples(experiment.settle_s, ts);
  plan.level_min_m = reach.level_min_m;
  plan.level_max_m = reach.level_max_m;
  plan.max_invalid_samples = experiment.max_invalid_samples;
  const double nominal = reach.nominal_setpoint.value_or(1.0);
  if (experiment.mode == core::ExperimentMode::kDesign) {
    core::ExperimentDesignRequest request;
    request.nominal_flow_m3s = reach.nominal_inflow_m3s;
    request.expected_delay_s = reach.expected_delay_s;
    request.sample_time_s = ts;
    request.amplitude_percent = experiment.amplitude_percent;
    request.duration_factor = experiment.duration_factor;
    const core::ExperimentDesign design = core::DesignPrbsExperiment(request);
    plan.prbs.clock_period_samples = design.clock_period_samples;
    plan.prbs.order = design.order;
    plan.excite_samples = design.num_samples;
    if (reach.actuator_gain_m3s_per_unit) {
      plan.prbs.amplitude = design.amplitude_m3s / std::abs(*reach.actuator_gain_m3s_per_unit);
    } else {
      // Flow proportional to the setting: the same percentage of the nominal setpoint.
      wiring.amplitude_fraction = experiment.amplitude_percent / 100.0;
      plan.prbs.amplitude = wiring.amplitude_fraction * std::abs(nominal);
    }
  } else {
    plan.prbs.amplitude = experiment.amplitude;
    plan.prbs.clock_period_samples = std::max(1, Samples(experiment.clock_period_s, ts));
    plan.prbs.order = experiment.order;
    plan.excite_samples = static_cast<std::int64_t>(experiment.periods) * ((std::int64_t{1} << experiment.order) - 1) *
                          plan.prbs.clock_period_samples;
  }
  plan.prbs.nominal = nominal;
  wiring.pipeline.experiment = plan;
  wiring.start_experiment_on_start = experiment.start == core::ExperimentStart::kOnStart;
}

}  // namespace

DaemonPlan BuildDaemonPlan(const core::DaemonConfig& config, const std::string& config_path,
                           const std::string& config_text) {
  DaemonPlan plan;
  plan.config_path = config_path;
  plan.config_text = config_text;
  plan.lcm_url = config.lcm.url;
  plan.channel_prefix = config.lcm.channel_prefix;
  plan.state_directory = config.daemon.state_directory;
  plan.commands_enabled = config.commands.enabled;
  plan.command_key_file = config.commands.key_file;
  plan.command_max_clock_skew_s = config.commands.max_clock_skew_s;
  for (const core::PlcConfig& plc : config.plcs) {
    PlcWiring wiring;
    wiring.link = BuildModbusConfig(plc);
    wiring.poller = BuildPollerConfig(config, plc);
    if (config.daemon.heartbeat) {
      const core::ChannelConfig* channel = config.FindChannel(config.daemon.heartbeat->channel);
      if (channel != nullptr && channel->plc == plc.name) {
        wiring.heartbeat_channel = ChannelIndex(wiring.poller, channel->name);
        wiring.heartbeat_period_s = config.daemon.heartbeat->period_s;
      }
    }
    plan.plcs.push_back(std::move(wiring));
  }
  for (const core::ReachConfig& reach : config.reaches) {
    const core::ChannelConfig* level = config.FindChannel(reach.level);
    if (level == nullptr) throw std::invalid_argument("reach '" + reach.name + "': no level channel");
    const auto plc = std::find_if(config.plcs.begin(), config.plcs.end(),
                                  [&](const core::PlcConfig& p) { return p.name == level->plc; });
    if (plc == config.plcs.end()) throw std::invalid_argument("reach '" + reach.name + "': no PLC");
    ReachWiring wiring;
    wiring.name = reach.name;
    wiring.plc = static_cast<int>(plc - config.plcs.begin());
    const drivers::PollerConfig& poller = plan.plcs[static_cast<std::size_t>(wiring.plc)].poller;
    wiring.q_in = ChannelIndex(poller, reach.inflow);
    wiring.q_out = ChannelIndex(poller, reach.outflow);
    wiring.level = ChannelIndex(poller, reach.level);
    wiring.actuator = ChannelIndex(poller, reach.actuator);
    const double ts = core::ReachSampleTimeS(config, reach);
    wiring.pipeline.sample_time_s = ts;
    wiring.pipeline.online_id_enabled =
        std::find(reach.online_models.begin(), reach.online_models.end(), core::OnlineModel::kId) !=
        reach.online_models.end();
    wiring.pipeline.online_id.min_delay_samples = Samples(reach.min_delay_s, ts);
    wiring.pipeline.online_id.max_delay_samples = std::max(wiring.pipeline.online_id.min_delay_samples,
                                                           Samples(reach.max_delay_s, ts));
    wiring.pipeline.online_id.rls.method = reach.rls_method;
    wiring.pipeline.online_id.rls.forgetting = reach.forgetting;
    wiring.pipeline.batch.fit.min_nk = wiring.pipeline.online_id.min_delay_samples;
    wiring.pipeline.batch.fit.max_nk = wiring.pipeline.online_id.max_delay_samples;
    wiring.nominal_from_reading = !reach.nominal_setpoint.has_value();
    for (const core::ExperimentConfig& experiment : config.experiments) {
      if (experiment.reach == reach.name) {
        PlanExperiment(reach, experiment, ts, wiring);
        break;
      }
    }
    plan.reaches.push_back(std::move(wiring));
  }
  return plan;
}

}  // namespace canalid::daemon
