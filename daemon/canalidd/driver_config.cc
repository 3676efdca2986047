#include "daemon/canalidd/driver_config.h"

namespace canalid::daemon {

std::variant<drivers::ModbusTcpConfig, drivers::ModbusRtuConfig> BuildModbusConfig(
    const config::PlcConfig& plc) {
  if (plc.transport == config::PlcTransport::kTcp) {
    drivers::ModbusTcpConfig tcp;
    tcp.host = plc.host;
    tcp.port = plc.port;
    tcp.unit_id = plc.unit_id;
    tcp.response_timeout_s = plc.response_timeout_s;
    tcp.connect_timeout_s = plc.connect_timeout_s;
    return tcp;
  }
  drivers::ModbusRtuConfig rtu;
  rtu.device = plc.device;
  rtu.baud = plc.baud;
  rtu.parity = plc.parity;
  rtu.data_bits = plc.data_bits;
  rtu.stop_bits = plc.stop_bits;
  rtu.unit_id = plc.unit_id;
  rtu.response_timeout_s = plc.response_timeout_s;
  return rtu;
}

drivers::PollerConfig BuildPollerConfig(const config::DaemonConfig& config,
                                        const config::PlcConfig& plc) {
  drivers::PollerConfig poller;
  poller.plc_name = plc.name;
  poller.period_s = plc.poll_period_s;
  poller.max_gap_registers = plc.max_gap_registers;
  poller.backoff_initial_s = plc.backoff_initial_s;
  poller.backoff_max_s = plc.backoff_max_s;
  poller.timeouts_before_reconnect = plc.timeouts_before_reconnect;
  for (const config::ChannelConfig& ch : config.channels) {
    if (ch.plc != plc.name) continue;
    drivers::PollChannel& p = poller.channels.emplace_back();
    p.name = ch.name;
    p.kind = ch.table == config::RegisterTable::kInput ? drivers::RegisterKind::kInput
                                                       : drivers::RegisterKind::kHolding;
    p.address = ch.address;
    p.scaling = {ch.type, ch.word_order, ch.scale, ch.offset, ch.valid_min, ch.valid_max};
    p.writable = ch.writable;
    // The limiter runs on wall-clock time; the configured rate is per plant second.
    if (ch.writable) {
      p.limits = {ch.setpoint_min, ch.setpoint_max, ch.max_rate_per_s * config.daemon.time_scale};
    }
  }
  return poller;
}

int PollerChannelIndex(const drivers::PollerConfig& poller, const std::string& name) {
  for (std::size_t i = 0; i < poller.channels.size(); ++i) {
    if (poller.channels[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace canalid::daemon
