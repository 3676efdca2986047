#pragma once
#include <string>
#include <variant>

#include "daemon/config/daemon_config.h"
#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// The link settings of `plc` for drivers::ModbusPort (TCP or RTU, by its transport).
std::variant<drivers::ModbusTcpConfig, drivers::ModbusRtuConfig> BuildModbusConfig(
    const config::PlcConfig& plc);

/// The poller of `plc`: its period and backoff, and every channel of `config` on this PLC in file
/// order, with scaling (type, word order, scale, offset, valid range) and, for writable channels,
/// the setpoint limits (max_rate_per_s is per plant second in the file and per wall second in the
/// poller: multiplied by time_scale).  PollSample::values[i] is then the i-th such channel.
drivers::PollerConfig BuildPollerConfig(const config::DaemonConfig& config,
                                        const config::PlcConfig& plc);

/// Index of the channel `name` in poller.channels (so in PollSample::values and for
/// PlcPoller::RequestWrite), or -1 when it is not polled by this poller.
int PollerChannelIndex(const drivers::PollerConfig& poller, const std::string& name);

}  // namespace canalid::daemon
