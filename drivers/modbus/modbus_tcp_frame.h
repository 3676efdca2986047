#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/modbus/plc_port.h"

namespace canalid::drivers {

/// Modbus TCP application data units (Modbus Messaging on TCP/IP Implementation Guide 1.0b, 3.1):
/// a 7-byte MBAP header (transaction id, protocol id 0, length of what follows, unit id) and the
/// PDU (function code and data).
///
/// libmodbus 3.1.6 checks only a reply's transaction id (and its protocol id with a test that lets
/// 0x0001 through); it reads as many bytes as the function code implies, whatever the MBAP length
/// says, and takes any unit id. ModbusPort therefore frames TCP requests itself with these pure
/// functions, which check every header field of a reply against its request and name the first
/// field that is wrong (ReplyFault).
inline constexpr std::size_t kMbapHeaderBytes = 7;
/// Largest PDU (Modbus application protocol 1.1b3, 4.1): the MBAP length is at most 1 + 253.
inline constexpr std::size_t kMaxPduBytes = 253;
inline constexpr std::size_t kMaxAduBytes = kMbapHeaderBytes - 1 + 1 + kMaxPduBytes;

/// One request ADU, built by the functions below, with what its reply must match.
struct TcpRequest {
  std::array<uint8_t, kMaxAduBytes> bytes{};
  std::size_t size = 0;
  uint16_t transaction_id = 0;
  uint8_t unit_id = 0;
  uint8_t function = 0;
  uint16_t address = 0;
  uint16_t count = 0;  ///< registers read or written (1 for function 6)
  uint16_t value = 0;  ///< function 6: the value written

  std::span<const uint8_t> adu() const { return {bytes.data(), size}; }
};

/// Function 3 (holding) or 4 (input). `count` must be 1..kMaxReadRegisters and `address + count`
/// at most 65536 (checked by the caller, ModbusPort).
TcpRequest ReadRegistersRequest(uint16_t transaction_id, uint8_t unit_id, RegisterKind kind,
                                uint16_t address, uint16_t count);
/// Function 6.
TcpRequest WriteRegisterRequest(uint16_t transaction_id, uint8_t unit_id, uint16_t address,
                                uint16_t value);
/// Function 16; `values.size()` must be 1..kMaxWriteRegisters.
TcpRequest WriteRegistersRequest(uint16_t transaction_id, uint8_t unit_id, uint16_t address,
                                 std::span<const uint16_t> values);

/// The PDU length the MBAP header announces (its length field minus the unit id), or the fault
/// that makes the header unusable: a protocol id other than 0 (kProtocolId) or a length outside
/// 2..254 (kLength). `header` must hold kMbapHeaderBytes bytes.
struct HeaderCheck {
  ReplyFault fault = ReplyFault::kNone;
  std::size_t pdu_bytes = 0;
};
HeaderCheck CheckReplyHeader(std::span<const uint8_t> header);

/// A whole reply (header and the PDU its length announced) checked against its request, in
/// this order: at least a header and one byte, transaction id, protocol id, length, unit id, then
/// the PDU: an exception reply (function | 0x80, one code byte of 1..11) gives
/// PlcErrorKind::kException with its code; any other
/// function than the request's, a byte count other than 2 x count, a PDU length that does not fit
/// the function, or a write reply that does not echo the request is kBadData with the fault.
PlcStatus CheckReply(const TcpRequest& request, std::span<const uint8_t> reply);

/// The registers of a reply to a read that CheckReply accepted; `out.size()` == request.count.
void ReplyRegisters(std::span<const uint8_t> reply, std::span<uint16_t> out);

}  // namespace canalid::drivers
