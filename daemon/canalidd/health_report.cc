#include "daemon/canalidd/health_report.h"

namespace canalid::daemon {
namespace {

// Health counter suffixes as docs/lcm-channels.md names them (PlcErrorKindName is for people).
const char* ReadErrorCounterName(drivers::PlcErrorKind kind) {
  switch (kind) {
    case drivers::PlcErrorKind::kNone:
      return "ok";
    case drivers::PlcErrorKind::kTimeout:
      return "timeout";
    case drivers::PlcErrorKind::kException:
      return "exception";
    case drivers::PlcErrorKind::kDisconnected:
      return "disconnected";
    case drivers::PlcErrorKind::kBadData:
      return "bad_data";
    case drivers::PlcErrorKind::kConfig:
      return "config";
  }
  return "unknown";
}

}  // namespace

HealthReport PlcHealth(const std::string& plc_name, const drivers::PollerCounters& c) {
  HealthReport report;
  report.component = "plc." + plc_name;
  report.counters = {{"polls", c.polls},
                     {"block_reads_ok", c.block_reads_ok},
                     {"connect_failures", c.connect_failures},
                     {"reconnects", c.reconnects},
                     {"samples_dropped", c.samples_dropped},
                     {"overruns", c.overruns},
                     {"writes_ok", c.writes_ok},
                     {"writes_failed", c.writes_failed}};
  for (int k = 1; k < drivers::kPlcErrorKindCount; ++k) {
    report.counters.emplace_back(
        std::string("read_errors.") + ReadErrorCounterName(static_cast<drivers::PlcErrorKind>(k)),
        c.read_errors[static_cast<std::size_t>(k)]);
  }
  for (int k = 1; k < drivers::kReplyFaultCount; ++k) {
    report.counters.emplace_back(
        std::string("bad_replies.") + drivers::ReplyFaultName(static_cast<drivers::ReplyFault>(k)),
        c.reply_faults[static_cast<std::size_t>(k)]);
  }
  report.gauges = {{"last_round_trip_s", c.last_round_trip_s},
                   {"connected", c.connected ? 1.0 : 0.0},
                   {"current_backoff_s", c.current_backoff_s}};
  return report;
}

HealthReport BusHealth(int64_t handler_failures, int64_t publish_failures, int64_t losses,
                       int64_t reconnects) {
  HealthReport bus;
  bus.component = "lcm";
  bus.counters = {{"handler_failures", handler_failures},
                  {"publish_failures", publish_failures},
                  {"losses", losses},
                  {"reconnects", reconnects}};
  return bus;
}

HealthReport CommandHealth(const drivers::CommandReceiver& receiver) {
  HealthReport commands;
  commands.component = "commands";
  for (int v = 0; v < drivers::kNumCommandVerdicts; ++v) {
    const auto verdict = static_cast<drivers::CommandVerdict>(v);
    commands.counters.emplace_back(std::string("verdicts.") + drivers::CommandVerdictName(verdict),
                                   receiver.count(verdict));
  }
  commands.counters.emplace_back("callback_failures", receiver.callback_failures());
  return commands;
}

HealthReport ReachHealth(const std::string& reach, const core::ReachSampleProcessor& pipeline) {
  HealthReport report;
  report.component = "reach." + reach;
  report.counters = {{"samples", pipeline.samples()}};
  if (const core::OnlineIntegratorDelayBank* bank = pipeline.online_id()) {
    const core::IntegratorDelayBankHealth& h = bank->health();
    report.counters.insert(report.counters.end(), {{"bad_flow_samples", h.bad_flow_samples},
                                                   {"bad_level_samples", h.bad_level_samples},
                                                   {"delay_switches", h.switches}});
  }
  return report;
}

}  // namespace canalid::daemon
