#pragma once
#include <array>
#include <cstddef>
#include <string>
#include <variant>

#include "drivers/modbus/modbus_tcp_frame.h"
#include "drivers/modbus/plc_port.h"

// libmodbus's context type, kept out of our headers (its name is libmodbus's).
struct _modbus;  // NOLINT(bugprone-reserved-identifier)

namespace canalid::drivers {

/// Modbus TCP link settings.
struct ModbusTcpConfig {
  std::string host = "127.0.0.1";   ///< name or address (resolved at each connect)
  int port = 502;                   ///< 1..65535
  int unit_id = 1;                  ///< 0..255 (TCP gateways route on it; plain servers ignore it)
  double response_timeout_s = 0.2;  ///< per request, (0, 60]
  double connect_timeout_s = 1.0;   ///< TCP connect, (0, 60]
};

/// Modbus RTU (serial) link settings.
struct ModbusRtuConfig {
  std::string device;               ///< e.g. /dev/ttyUSB0
  int baud = 19200;                 ///< > 0
  char parity = 'E';                ///< 'N', 'E' or 'O'
  int data_bits = 8;                ///< 5..8
  int stop_bits = 1;                ///< 1 or 2
  int unit_id = 1;                  ///< 1..247
  double response_timeout_s = 0.2;  ///< per request, (0, 60]
};

/// @throws std::invalid_argument naming the field, its value and the allowed range.
void ValidateModbusConfig(const ModbusTcpConfig& config);
void ValidateModbusConfig(const ModbusRtuConfig& config);

/// PlcPort over libmodbus (TCP or RTU). The libmodbus context is created by the first Connect()
/// (so on the thread that will use it) and freed by the destructor. Not thread-safe. After
/// kDisconnected the link is closed.
///
/// Over TCP libmodbus connects, but the requests are framed and the replies read and checked
/// here (modbus_tcp_frame.h: every MBAP field, the PDU length, the echo of a write), each request
/// with its own transaction id, the whole exchange bounded by the response timeout. A whole frame
/// answering one of the last 8 requests (a reply that came after its request timed out) is
/// skipped, at most 8 of them; a frame that cannot be delimited (bad protocol id or MBAP length,
/// a PDU length its function does not allow, cut short by the timeout), more late frames than
/// that, or a request only partly sent drops the link (kDisconnected), since what follows on the
/// stream cannot be trusted. Nothing is flushed: each exchange ends at a frame boundary.
///
/// RTU requests go through libmodbus, which checks the slave address and the CRC; its errno
/// values go through TranslateModbusErrno, and after kTimeout or kBadData pending bytes are
/// flushed so a late reply is not taken for the next one.
class ModbusPort final : public PlcPort {
 public:
  /// @throws std::invalid_argument on a bad config (see ValidateModbusConfig).
  explicit ModbusPort(const ModbusTcpConfig& config);
  explicit ModbusPort(const ModbusRtuConfig& config);
  ~ModbusPort() override;
  ModbusPort(const ModbusPort&) = delete;
  ModbusPort& operator=(const ModbusPort&) = delete;

  PlcStatus Connect() noexcept override;
  void Close() noexcept override;
  bool connected() const noexcept override { return connected_; }
  double response_timeout_s() const noexcept override;
  PlcStatus ReadRegisters(RegisterKind kind, int address,
                          std::span<uint16_t> out) noexcept override;
  PlcStatus WriteRegister(int address, uint16_t value) noexcept override;
  PlcStatus WriteRegisters(int address, std::span<const uint16_t> values) noexcept override;

 private:
  PlcStatus CreateContext() noexcept;
  /// After a failed libmodbus (RTU) call: translates errno, closes on kDisconnected, flushes on
  /// kTimeout and kBadData.
  PlcStatus Failed() noexcept;
  /// TCP: sends `request` and reads its reply into reply_ (reply_size_ bytes), checked.
  PlcStatus TcpExchange(const TcpRequest& request) noexcept;
  bool tcp() const noexcept { return std::holds_alternative<ModbusTcpConfig>(config_); }

  std::variant<ModbusTcpConfig, ModbusRtuConfig> config_;
  // The fields both configs share, copied out so that reading them cannot throw (std::visit can).
  int unit_id_ = 0;
  double response_timeout_s_ = 0.0;
  _modbus* ctx_ = nullptr;
  bool connected_ = false;
  uint16_t next_transaction_id_ = 1;
  std::array<uint8_t, kMaxAduBytes> reply_{};
  std::size_t reply_size_ = 0;
};

}  // namespace canalid::drivers
