#pragma once
#include <cstdint>
#include <span>

namespace canalid::drivers {

/// The two 16-bit register tables a PLC channel can live in (Modbus function 3 and 4).
enum class RegisterKind { kHolding, kInput };

/// Largest block one Modbus read may carry (Modbus application protocol 1.1b3, 6.3 and 6.4).
inline constexpr int kMaxReadRegisters = 125;
/// Largest block one Modbus write-multiple-registers request may carry (6.12).
inline constexpr int kMaxWriteRegisters = 123;

/// Why a PLC request failed. Every libmodbus errno maps to exactly one of these (see
/// TranslateModbusErrno), so code above the port never sees errno. The numeric values are those
/// of canalid.sample_t STATUS_* (checked in tests/drivers/lcm_bus_test.cc).
enum class PlcErrorKind {
  kNone,
  kTimeout,       ///< no (complete) reply within the response timeout
  kException,     ///< the PLC answered with a Modbus exception; see PlcStatus::exception_code
  kDisconnected,  ///< no connection, or it was lost (reset, broken pipe, refused, EOF)
  kBadData,       ///< a reply that does not match the request (CRC, length, transaction id...)
  kConfig,        ///< a bad request or adapter setting (count > 125, bad address, bad device)
};
inline constexpr int kPlcErrorKindCount = 6;

/// Which part of a Modbus TCP reply did not match its request (ModbusPort checks every MBAP
/// header field itself; libmodbus does not). Counted by the poller under these names.
enum class ReplyFault {
  kNone,
  kTransactionId,  ///< not the transaction id of the request (e.g. a late reply to an old one)
  kProtocolId,     ///< MBAP protocol id other than 0
  kLength,         ///< MBAP length outside 2..254, or not the length the function implies
  kUnitId,         ///< not the unit id of the request
  kFunction,       ///< a function other than the request's (or its exception form with code 1..11)
  kByteCount,      ///< a read reply whose byte count is not 2 x the registers asked for
  kEcho,           ///< a write reply that does not echo the address, value or count written
  kTruncated,      ///< the response timeout struck inside a reply (fewer bytes than announced)
};
inline constexpr int kReplyFaultCount = 9;

/// The counter suffix of a fault ("transaction_id", "protocol_id", ... as docs/lcm-channels.md).
const char* ReplyFaultName(ReplyFault fault);

/// Outcome of one PLC request. Plain value, never thrown.
struct PlcStatus {
  PlcErrorKind kind = PlcErrorKind::kNone;
  /// Modbus exception code when kind == kException (1 illegal function, 2 illegal data address,
  /// 3 illegal data value, 4 server device failure, 5 acknowledge, 6 server busy, ...), else 0.
  int exception_code = 0;
  /// The errno the adapter saw (0 if none), kept for logs only.
  int sys_errno = 0;
  /// Over Modbus TCP, the reply field that was wrong: with kBadData, the refused reply's; with
  /// kDisconnected, the framing that was lost (protocol id, MBAP length, a reply cut short), after
  /// which the link is dropped; kTransactionId with any kind (even kNone), a whole frame of
  /// another transaction (a late reply) that was skipped while waiting for this one.
  ReplyFault reply_fault = ReplyFault::kNone;

  bool ok() const { return kind == PlcErrorKind::kNone; }
  static PlcStatus Ok() { return {}; }
};

/// Short English name ("timeout", "modbus exception" ...).
const char* PlcErrorKindName(PlcErrorKind kind);

/// A PLC reached over some link (Modbus TCP, RTU, or a fake in tests).
///
/// Threading: an implementation is used by one thread at a time (the poller thread); it is not
/// thread-safe. Every call blocks for at most the adapter's timeouts. Nothing here throws:
/// failures are PlcStatus values. Addresses are 0-based protocol addresses (register 40001 of
/// the old numbering is holding address 0).
class PlcPort {
 public:
  virtual ~PlcPort() = default;

  /// Opens the link (creating any library context on the calling thread).
  virtual PlcStatus Connect() noexcept = 0;
  /// Closes the link; safe to call when not connected.
  virtual void Close() noexcept = 0;
  virtual bool connected() const noexcept = 0;
  /// Longest wait for one reply, in seconds (0 for links that never wait, like a fake).
  virtual double response_timeout_s() const noexcept = 0;

  /// Reads out.size() registers (1..kMaxReadRegisters) starting at `address`.
  virtual PlcStatus ReadRegisters(RegisterKind kind, int address,
                                  std::span<uint16_t> out) noexcept = 0;
  /// Writes one holding register (function 6).
  virtual PlcStatus WriteRegister(int address, uint16_t value) noexcept = 0;
  /// Writes values.size() holding registers (1..kMaxWriteRegisters) from `address` (function 16).
  virtual PlcStatus WriteRegisters(int address, std::span<const uint16_t> values) noexcept = 0;
};

}  // namespace canalid::drivers
