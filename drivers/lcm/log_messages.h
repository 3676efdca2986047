#pragma once
#include <canalid/config_t.hpp>
#include <canalid/experiment_state_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include <cstdint>
#include <functional>
#include <string>

#include "drivers/lcm/log_reader.h"

namespace canalid::drivers {

/// Receives the canalid messages of a log in order.  The message objects are reused between
/// calls (copy what must outlive the call).
class LogMessageVisitor {
 public:
  virtual ~LogMessageVisitor() = default;
  virtual void OnConfig(const canalid::config_t& /*config*/, const LogEvent& /*event*/) {}
  /// `plc` is the channel's suffix after `<prefix>SAMPLE_`.
  virtual void OnSample(const std::string& /*plc*/, const canalid::sample_t& /*sample*/,
                        const LogEvent& /*event*/) {}
  virtual void OnExperiment(const canalid::experiment_state_t& /*state*/,
                            const LogEvent& /*event*/) {}
  virtual void OnModel(const canalid::model_snapshot_t& /*model*/, const LogEvent& /*event*/) {}
};

struct LogScanOptions {
  /// The channel prefix of the daemon to read ("CANALID_"); empty: the prefix of the first
  /// `<prefix>CONFIG` message that decodes as canalid.config_t (messages before it are skipped).
  std::string prefix;
  /// Called every `progress_every_events` events and at the end with bytes read and the log size.
  std::function<void(std::uint64_t bytes, std::uint64_t size)> progress;
  std::int64_t progress_every_events = 65536;
};

struct LogScanResult {
  LogEnd end = LogEnd::kReading;
  std::string problem;  ///< "LOG: byte N: ..." when the log is damaged, "" otherwise
  std::string prefix;   ///< the prefix read
  std::int64_t events = 0;
  std::int64_t samples = 0;
  std::int64_t skipped_events = 0;  ///< other prefixes, other channels
  std::uint64_t bytes = 0;          ///< up to the end of the last whole event used
};

/// Reads the LCM log `path` (drivers::LogReader: lossless, in process) and hands the messages of
/// one canalid daemon (channels `<prefix>CONFIG`, `<prefix>SAMPLE_<plc>`,
/// `<prefix>EXPERIMENT_<reach>`, `<prefix>MODEL_<reach>`) to `visitor` in log order.  Stops at
/// the first damage: a truncated or corrupt event, or a message of ours that does not decode as
/// its type (reported as corrupt with its byte offset); everything before it has been delivered.
/// Exceptions thrown by the visitor propagate.
/// @throws std::runtime_error when the file cannot be opened.
LogScanResult ScanCanalidLog(const std::string& path, const LogScanOptions& options,
                             LogMessageVisitor& visitor);

}  // namespace canalid::drivers
