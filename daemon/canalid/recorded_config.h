#pragma once
#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>

#include <memory>
#include <optional>
#include <string>

#include "core/reach/reach_controller.h"
#include "daemon/config/daemon_config.h"
#include "drivers/lcm/log_reader.h"

namespace canalid::cli {

/// The daemon configuration that applies to a log: the one given on the command line (fixed), or
/// the latest `<prefix>CONFIG` message of the log, parsed with the daemon's own reader.
class RecordedConfig final {
 public:
  /// `given` (from --config) is used throughout and the log's messages are ignored.
  explicit RecordedConfig(std::optional<config::DaemonConfig> given);

  /// A configuration message of the log.  Returns true when it is now the configuration.
  /// @throws InputError naming the log position when the recorded text does not parse.
  bool OnConfig(const canalid::config_t& message, const drivers::LogEvent& event,
                const std::string& log_path);

  /// Null until a configuration is known.
  const std::shared_ptr<const config::DaemonConfig>& config() const { return config_; }
  bool given() const { return given_; }

  /// The PLC of a reach (the PLC of its level channel); empty if it does not resolve.
  std::string ReachPlc(const config::ReachConfig& reach) const;

  /// Runner options of `reach` with channel indices into `sample`'s channel list.
  /// @throws InputError when a channel of the reach is not in the sample.
  core::ReachControllerOptions RunnerOptions(const config::ReachConfig& reach,
                                             const canalid::sample_t& sample,
                                             const std::string& where) const;

 private:
  std::shared_ptr<const config::DaemonConfig> config_;
  bool given_ = false;
};

/// Index of channel `name` in the sample's channel list, or -1.
int SampleChannelIndex(const canalid::sample_t& sample, const std::string& name);

}  // namespace canalid::cli
