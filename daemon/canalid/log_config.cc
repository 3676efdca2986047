#include "daemon/canalid/log_config.h"

#include <utility>

#include "core/daemon_plan.h"
#include "daemon/canalid/input_error.h"
#include "daemon/config/config_loader.h"

namespace canalid::cli {

LogConfig::LogConfig(std::optional<core::DaemonConfig> given) {
  if (given) {
    config_ = std::make_shared<const core::DaemonConfig>(std::move(*given));
    given_ = true;
  }
}

bool LogConfig::OnConfig(const canalid::config_t& message, const drivers::LogEvent& event,
                         const std::string& log_path) {
  if (given_) return false;
  const std::string name = log_path + " (configuration at byte " + std::to_string(event.offset) +
                           ", from " + message.path + ")";
  try {
    config_ =
        std::make_shared<const core::DaemonConfig>(daemon::ParseDaemonConfig(message.text, name));
  } catch (const daemon::ConfigError& e) {
    throw InputError(std::string("the configuration recorded in the log is not valid:\n") +
                     e.what());
  }
  return true;
}

std::string LogConfig::ReachPlc(const core::ReachConfig& reach) const {
  if (!config_) return {};
  const core::PlcConfig* plc = config_->FindReachPlc(reach);
  return plc == nullptr ? std::string() : plc->name;
}

int SampleChannelIndex(const canalid::sample_t& sample, const std::string& name) {
  for (std::size_t i = 0; i < sample.channel_names.size(); ++i) {
    if (sample.channel_names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

core::ReachRunnerOptions LogConfig::RunnerOptions(const core::ReachConfig& reach,
                                                  const canalid::sample_t& sample,
                                                  const std::string& where) const {
  try {
    return core::BuildReachRunnerOptions(config_, reach, [&](const std::string& name) {
      const int index = SampleChannelIndex(sample, name);
      if (index < 0) {
        throw std::invalid_argument("channel '" + name + "' of reach '" + reach.name +
                                    "' is not in the samples of PLC '" + sample.source + "'");
      }
      return index;
    });
  } catch (const std::invalid_argument& e) {
    throw InputError(where + ": " + e.what());
  }
}

}  // namespace canalid::cli
