#include "daemon/canalidd/plan_builder.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "daemon/canalidd/driver_config.h"
#include "daemon/config/plan_from_config.h"

namespace canalid::daemon {
namespace {

int ChannelIndex(const drivers::PollerConfig& poller, const std::string& name) {
  for (std::size_t i = 0; i < poller.channels.size(); ++i) {
    if (poller.channels[i].name == name) return static_cast<int>(i);
  }
  throw std::invalid_argument("channel '" + name + "' is not polled on PLC '" + poller.plc_name +
                              "'");
}

}  // namespace

DaemonPlan BuildDaemonPlan(const config::DaemonConfig& config, const std::string& config_path,
                           const std::string& config_text) {
  // Shared by every reach's experiment factory, which may run long after this returns.
  const auto shared = std::make_shared<const config::DaemonConfig>(config);
  DaemonPlan plan;
  plan.config_path = config_path;
  plan.config_text = config_text;
  plan.lcm_url = config.lcm.url;
  plan.channel_prefix = config.lcm.channel_prefix;
  plan.state_directory = config.daemon.state_directory;
  plan.commands_enabled = config.commands.enabled;
  plan.command_key_file = config.commands.key_file;
  plan.command_max_clock_skew_s = config.commands.max_clock_skew_s;
  plan.command_kinds = config.commands.accepted;
  if (const auto listen = config::ParseListenAddress(config.results.listen)) {
    plan.results_enabled = true;
    plan.results_host = listen->host;
    plan.results_port = listen->port;
  }
  plan.results_max_clients = config.results.max_clients;
  for (const config::PlcConfig& plc : config.plcs) {
    PlcWiring wiring;
    wiring.link = BuildModbusConfig(plc);
    wiring.poller = BuildPollerConfig(config, plc);
    if (config.daemon.heartbeat) {
      const config::ChannelConfig* channel = config.FindChannel(config.daemon.heartbeat->channel);
      if (channel != nullptr && channel->plc == plc.name) {
        wiring.heartbeat_channel = ChannelIndex(wiring.poller, channel->name);
        wiring.heartbeat_period_s = config.daemon.heartbeat->period_s;
      }
    }
    plan.plcs.push_back(std::move(wiring));
  }
  for (const config::ReachConfig& reach : config.reaches) {
    const config::PlcConfig* plc = config.FindReachPlc(reach);
    if (plc == nullptr) {
      throw std::invalid_argument("reach '" + reach.name + "': no PLC");
    }
    ReachWiring wiring;
    wiring.plc = static_cast<int>(plc - config.plcs.data());
    const drivers::PollerConfig& poller = plan.plcs[static_cast<std::size_t>(wiring.plc)].poller;
    wiring.runner = config::BuildReachControllerOptions(
        shared, reach, [&](const std::string& name) { return ChannelIndex(poller, name); });
    wiring.model_publish_every = std::max<std::int64_t>(
        1, std::llround(reach.model_publish_period_s / config::ReachSampleTimeS(config, reach)));
    plan.reaches.push_back(std::move(wiring));
  }
  std::vector<std::string> reach_names;
  for (const config::ReachConfig& reach : config.reaches) reach_names.push_back(reach.name);
  plan.joints = config::BuildJointExperiments(config, reach_names);
  return plan;
}

}  // namespace canalid::daemon
