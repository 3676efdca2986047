#include "drivers/modbus/modbus_tcp_frame.h"

namespace canalid::drivers {
namespace {

constexpr uint8_t kReadHolding = 3;
constexpr uint8_t kReadInput = 4;
constexpr uint8_t kWriteSingle = 6;
constexpr uint8_t kWriteMultiple = 16;
constexpr uint8_t kExceptionBit = 0x80;

uint16_t Word(std::span<const uint8_t> bytes, std::size_t at) {
  return static_cast<uint16_t>((bytes[at] << 8) | bytes[at + 1]);
}

void PutWord(TcpRequest& r, uint16_t word) {
  r.bytes[r.size++] = static_cast<uint8_t>(word >> 8);
  r.bytes[r.size++] = static_cast<uint8_t>(word & 0xff);
}

// The MBAP header, unit id and function; the length is filled in by Finish.
TcpRequest Begin(uint16_t transaction_id, uint8_t unit_id, uint8_t function, uint16_t address) {
  TcpRequest r;
  r.transaction_id = transaction_id;
  r.unit_id = unit_id;
  r.function = function;
  r.address = address;
  PutWord(r, transaction_id);
  PutWord(r, 0);  // protocol id
  PutWord(r, 0);  // length, below
  r.bytes[r.size++] = unit_id;
  r.bytes[r.size++] = function;
  PutWord(r, address);
  return r;
}

void Finish(TcpRequest& r) {
  const auto length = static_cast<uint16_t>(r.size - (kMbapHeaderBytes - 1));
  r.bytes[4] = static_cast<uint8_t>(length >> 8);
  r.bytes[5] = static_cast<uint8_t>(length & 0xff);
}

PlcStatus Bad(ReplyFault fault) {
  PlcStatus s;
  s.kind = PlcErrorKind::kBadData;
  s.reply_fault = fault;
  return s;
}

// The PDU of an accepted header, against the request's function.
PlcStatus CheckPdu(const TcpRequest& request, std::span<const uint8_t> pdu) {
  if (pdu.size() < 2) return Bad(ReplyFault::kLength);  // every reply has a function and data
  const uint8_t function = pdu[0];
  if (function == (request.function | kExceptionBit)) {
    if (pdu.size() != 2) return Bad(ReplyFault::kLength);
    // Codes 1..11 are the Modbus exceptions (application protocol 1.1b3, 7); others are noise.
    if (pdu[1] < 1 || pdu[1] > 11) return Bad(ReplyFault::kFunction);
    PlcStatus s;
    s.kind = PlcErrorKind::kException;
    s.exception_code = pdu[1];
    return s;
  }
  if (function != request.function) return Bad(ReplyFault::kFunction);
  if (function == kReadHolding || function == kReadInput) {
    const std::size_t data_bytes = std::size_t{2} * request.count;
    if (pdu.size() != 2 + data_bytes) {
      // A byte count that agrees with the MBAP length but not with the request is the PLC
      // answering another question; one that disagrees with the length is a framing error.
      return pdu.size() == 2U + pdu[1] ? Bad(ReplyFault::kByteCount) : Bad(ReplyFault::kLength);
    }
    if (pdu[1] != data_bytes) return Bad(ReplyFault::kByteCount);
    return PlcStatus::Ok();
  }
  // Functions 6 and 16 echo the address and the value (6) or the count (16).
  if (pdu.size() != 5) return Bad(ReplyFault::kLength);
  const uint16_t second = function == kWriteSingle ? request.value : request.count;
  if (Word(pdu, 1) != request.address || Word(pdu, 3) != second) return Bad(ReplyFault::kEcho);
  return PlcStatus::Ok();
}

}  // namespace

TcpRequest ReadRegistersRequest(uint16_t transaction_id, uint8_t unit_id, RegisterKind kind,
                                uint16_t address, uint16_t count) {
  TcpRequest r = Begin(transaction_id, unit_id,
                       kind == RegisterKind::kHolding ? kReadHolding : kReadInput, address);
  r.count = count;
  PutWord(r, count);
  Finish(r);
  return r;
}

TcpRequest WriteRegisterRequest(uint16_t transaction_id, uint8_t unit_id, uint16_t address,
                                uint16_t value) {
  TcpRequest r = Begin(transaction_id, unit_id, kWriteSingle, address);
  r.count = 1;
  r.value = value;
  PutWord(r, value);
  Finish(r);
  return r;
}

TcpRequest WriteRegistersRequest(uint16_t transaction_id, uint8_t unit_id, uint16_t address,
                                 std::span<const uint16_t> values) {
  TcpRequest r = Begin(transaction_id, unit_id, kWriteMultiple, address);
  r.count = static_cast<uint16_t>(values.size());
  PutWord(r, r.count);
  r.bytes[r.size++] = static_cast<uint8_t>(2U * values.size());
  for (const uint16_t v : values) PutWord(r, v);
  Finish(r);
  return r;
}

HeaderCheck CheckReplyHeader(std::span<const uint8_t> header) {
  HeaderCheck check;
  if (Word(header, 2) != 0) {
    check.fault = ReplyFault::kProtocolId;
    return check;
  }
  const uint16_t length = Word(header, 4);
  if (length < 2 || length > 1 + kMaxPduBytes) {
    check.fault = ReplyFault::kLength;
    return check;
  }
  check.pdu_bytes = length - 1U;
  return check;
}

PlcStatus CheckReply(const TcpRequest& request, std::span<const uint8_t> reply) {
  if (reply.size() < kMbapHeaderBytes + 1) return Bad(ReplyFault::kLength);
  const auto header = reply.first(kMbapHeaderBytes);
  if (Word(header, 0) != request.transaction_id) return Bad(ReplyFault::kTransactionId);
  const HeaderCheck check = CheckReplyHeader(header);
  if (check.fault != ReplyFault::kNone) return Bad(check.fault);
  if (reply.size() != kMbapHeaderBytes + check.pdu_bytes) return Bad(ReplyFault::kLength);
  if (header[6] != request.unit_id) return Bad(ReplyFault::kUnitId);
  return CheckPdu(request, reply.subspan(kMbapHeaderBytes));
}

void ReplyRegisters(std::span<const uint8_t> reply, std::span<uint16_t> out) {
  const std::size_t data = kMbapHeaderBytes + 2;
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Word(reply, data + 2 * i);
}

}  // namespace canalid::drivers
