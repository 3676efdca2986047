// Modbus TCP replies as ModbusPort checks them (drivers/modbus/modbus_tcp_frame.h): the first
// bytes choose a request (function 3, 4, 6 or 16, transaction id, unit id, address, count, value),
// the rest is the reply the PLC sent.  Properties: nothing is read outside the reply; an accepted
// reply is exactly as long as its MBAP header says, carries the request's transaction and unit id
// and function, and (for a read) holds the registers asked for; a refusal names a field.
#include <algorithm>
#include <array>
#include <cstring>
#include <span>
#include <vector>

#include "drivers/modbus/modbus_tcp_frame.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using canalid::fuzz::Check;
namespace drivers = canalid::drivers;

uint16_t Word(const uint8_t* p) { return static_cast<uint16_t>(p[0] << 8 | p[1]); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  constexpr std::size_t kRequestBytes = 9;
  if (size < kRequestBytes) return 0;
  const int selector = data[0] % 4;
  const uint16_t transaction = Word(data + 1);
  const uint8_t unit = data[3];
  const uint16_t address = Word(data + 4);
  const uint16_t value = Word(data + 7);
  drivers::TcpRequest request;
  if (selector < 2) {
    const auto count = static_cast<uint16_t>(data[6] % drivers::kMaxReadRegisters + 1);
    if (address + count > 65536) return 0;  // ModbusPort refuses it before framing
    request = drivers::ReadRegistersRequest(
        transaction, unit,
        selector == 0 ? drivers::RegisterKind::kHolding : drivers::RegisterKind::kInput, address,
        count);
  } else if (selector == 2) {
    request = drivers::WriteRegisterRequest(transaction, unit, address, value);
  } else {
    const auto count = static_cast<std::size_t>(data[6] % drivers::kMaxWriteRegisters + 1);
    if (address + count > 65536) return 0;
    const std::vector<uint16_t> values(count, value);
    request = drivers::WriteRegistersRequest(transaction, unit, address, values);
  }
  Check(request.size >= drivers::kMbapHeaderBytes + 5 && request.size <= drivers::kMaxAduBytes,
        "a request fits one ADU");
  Check(Word(request.bytes.data() + 4) == request.size - 6, "a request's MBAP length is its own");

  // The reply in a buffer of its own size, so that ASan sees any read past it.
  const std::size_t reply_size = std::min(size - kRequestBytes, drivers::kMaxAduBytes);
  const std::vector<uint8_t> reply(data + kRequestBytes, data + kRequestBytes + reply_size);
  if (reply.size() >= drivers::kMbapHeaderBytes) {
    const drivers::HeaderCheck header =
        drivers::CheckReplyHeader(std::span(reply).first(drivers::kMbapHeaderBytes));
    Check(header.fault == drivers::ReplyFault::kNone
              ? header.pdu_bytes >= 1 && header.pdu_bytes <= drivers::kMaxPduBytes
              : header.pdu_bytes == 0,
          "a usable header frames a PDU of 1..253 bytes");
  }
  const drivers::PlcStatus s = drivers::CheckReply(request, reply);
  if (s.ok()) {
    Check(Word(reply.data()) == transaction && reply[6] == unit && reply[7] == request.function,
          "an accepted reply answers its request");
    Check(Word(reply.data() + 2) == 0 && Word(reply.data() + 4) == reply.size() - 6,
          "an accepted reply is framed by its MBAP header");
    if (selector < 2) {
      Check(reply.size() == drivers::kMbapHeaderBytes + 2 + std::size_t{2} * request.count,
            "an accepted read reply holds the registers asked for");
      std::array<uint16_t, drivers::kMaxReadRegisters> regs{};
      drivers::ReplyRegisters(reply, std::span(regs.data(), request.count));
    } else {
      Check(reply.size() == drivers::kMbapHeaderBytes + 5, "an accepted write reply is an echo");
    }
  } else if (s.kind == drivers::PlcErrorKind::kException) {
    Check(reply.size() == drivers::kMbapHeaderBytes + 2 && reply[7] == (request.function | 0x80) &&
              s.exception_code == reply[8],
          "an exception is a two-byte exception PDU with its code");
  } else {
    Check(s.kind == drivers::PlcErrorKind::kBadData &&
              s.reply_fault != drivers::ReplyFault::kNone &&
              s.reply_fault != drivers::ReplyFault::kTruncated,
          "a refused reply is bad data naming a field");
  }
  return 0;
}
