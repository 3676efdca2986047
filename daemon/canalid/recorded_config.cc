#include "daemon/canalid/recorded_config.h"

#include <utility>

#include "daemon/canalid/input_error.h"
#include "daemon/config/config_loader.h"
#include "daemon/config/plan_from_config.h"

namespace canalid::cli {

RecordedConfig::RecordedConfig(std::optional<config::DaemonConfig> given) {
  if (given) {
    config_ = std::make_shared<const config::DaemonConfig>(std::move(*given));
    given_ = true;
  }
}

bool RecordedConfig::OnConfig(const canalid::config_t& message, const drivers::LogEvent& event,
                              const std::string& log_path) {
  if (given_) return false;
  const std::string name = log_path + " (configuration at byte " + std::to_string(event.offset) +
                           ", from " + message.path + ")";
  try {
    config_ =
        std::make_shared<const config::DaemonConfig>(daemon::ParseDaemonConfig(message.text, name));
  } catch (const daemon::ConfigError& e) {
    throw InputError(std::string("the configuration recorded in the log is not valid:\n") +
                     e.what());
  }
  return true;
}

std::string RecordedConfig::ReachPlc(const config::ReachConfig& reach) const {
  if (!config_) return {};
  const config::PlcConfig* plc = config_->FindReachPlc(reach);
  return plc == nullptr ? std::string() : plc->name;
}

int SampleChannelIndex(const canalid::sample_t& sample, const std::string& name) {
  for (std::size_t i = 0; i < sample.channel_names.size(); ++i) {
    if (sample.channel_names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

core::ReachControllerOptions RecordedConfig::RunnerOptions(const config::ReachConfig& reach,
                                                           const canalid::sample_t& sample,
                                                           const std::string& where) const {
  try {
    return config::BuildReachControllerOptions(config_, reach, [&](const std::string& name) {
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
