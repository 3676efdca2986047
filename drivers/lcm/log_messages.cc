#include "drivers/lcm/log_messages.h"

#include <string_view>

#include "drivers/lcm/bus.h"

namespace canalid::drivers {
namespace {

constexpr std::string_view kConfig = "CONFIG";
constexpr std::string_view kSample = "SAMPLE_";
constexpr std::string_view kExperiment = "EXPERIMENT_";
constexpr std::string_view kModel = "MODEL_";

template <class Message>
bool Decode(const LogEvent& event, Message* message) {
  return DecodeMessage(event.data, *message);
}

}  // namespace

LogScanResult ScanCanalidLog(const std::string& path, const LogScanOptions& options,
                             LogMessageVisitor& visitor) {
  LogReader reader(path);
  LogScanResult result;
  result.prefix = options.prefix;
  canalid::config_t config;
  canalid::sample_t sample;
  canalid::experiment_state_t experiment;
  canalid::model_snapshot_t model;
  std::string plc;
  LogEvent event;
  auto corrupt = [&](const char* type) {
    result.end = LogEnd::kCorrupt;
    result.problem = path + ": byte " + std::to_string(event.offset) + ": event " +
                     std::to_string(event.event_number) + " on " + std::string(event.channel) +
                     " does not decode as " + type;
  };
  while (reader.Next(&event)) {
    ++result.events;
    if (options.progress && result.events % options.progress_every_events == 0)
      options.progress(reader.position(), reader.size_bytes());
    std::string_view channel = event.channel;
    if (result.prefix.empty()) {
      // The daemon publishes its configuration first; adopt the prefix of the first one.
      if (channel.size() <= kConfig.size() || !channel.ends_with(kConfig) ||
          !Decode(event, &config)) {
        ++result.skipped_events;
        continue;
      }
      result.prefix = std::string(channel.substr(0, channel.size() - kConfig.size()));
      visitor.OnConfig(config, event);
      result.bytes = reader.position();
      continue;
    }
    if (!channel.starts_with(result.prefix)) {
      ++result.skipped_events;
      continue;
    }
    channel.remove_prefix(result.prefix.size());
    if (channel == kConfig) {
      if (!Decode(event, &config)) {
        corrupt("canalid.config_t");
        break;
      }
      visitor.OnConfig(config, event);
    } else if (channel.starts_with(kSample)) {
      if (!Decode(event, &sample)) {
        corrupt("canalid.sample_t");
        break;
      }
      ++result.samples;
      plc.assign(channel.substr(kSample.size()));
      visitor.OnSample(plc, sample, event);
    } else if (channel.starts_with(kExperiment)) {
      if (!Decode(event, &experiment)) {
        corrupt("canalid.experiment_state_t");
        break;
      }
      visitor.OnExperiment(experiment, event);
    } else if (channel.starts_with(kModel)) {
      if (!Decode(event, &model)) {
        corrupt("canalid.model_snapshot_t");
        break;
      }
      visitor.OnModel(model, event);
    } else {
      ++result.skipped_events;
    }
    result.bytes = reader.position();
  }
  if (result.end == LogEnd::kReading) {
    result.end = reader.end();
    if (!reader.problem().empty()) result.problem = path + ": " + reader.problem();
    result.bytes = reader.position();
  }
  if (options.progress) options.progress(result.bytes, reader.size_bytes());
  return result;
}

}  // namespace canalid::drivers
