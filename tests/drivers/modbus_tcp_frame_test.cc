// Modbus TCP framing and reply checks (drivers/modbus/modbus_tcp_frame.h), against the request and
// reply examples of the Modbus Application Protocol Specification 1.1b3 (sections 6.3, 6.6, 6.12)
// wrapped in the MBAP header of the Messaging on TCP/IP Implementation Guide 1.0b (3.1.3).
#include "drivers/modbus/modbus_tcp_frame.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

namespace canalid::drivers {
namespace {

std::vector<uint8_t> Bytes(std::span<const uint8_t> s) { return {s.begin(), s.end()}; }

// MBAP header for transaction 0x1501, unit 0x11, followed by the PDU.
std::vector<uint8_t> Adu(const std::vector<uint8_t>& pdu, uint16_t transaction = 0x1501,
                         uint8_t unit = 0x11) {
  const auto length = static_cast<uint16_t>(pdu.size() + 1);
  std::vector<uint8_t> adu = {
      static_cast<uint8_t>(transaction >> 8), static_cast<uint8_t>(transaction & 0xff), 0,   0,
      static_cast<uint8_t>(length >> 8),      static_cast<uint8_t>(length & 0xff),      unit};
  for (const uint8_t b : pdu)
    adu.push_back(b);  // (insert of an empty PDU trips GCC 12's -Warray-bounds)
  return adu;
}

// Spec 6.3: read holding registers 108..110 (address 0x006B, count 3).
const std::vector<uint8_t> kReadPdu = {0x03, 0x00, 0x6B, 0x00, 0x03};
const std::vector<uint8_t> kReadReplyPdu = {0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64};

TcpRequest SpecRead() {
  return ReadRegistersRequest(0x1501, 0x11, RegisterKind::kHolding, 0x6B, 3);
}

ReplyFault FaultOf(const TcpRequest& request, const std::vector<uint8_t>& reply) {
  const PlcStatus s = CheckReply(request, reply);
  EXPECT_EQ(s.kind, PlcErrorKind::kBadData) << "a reply with a wrong field is bad data";
  return s.reply_fault;
}

TEST(ModbusTcpFrame, RequestsAreTheSpecificationsExamplesInAnMbapHeader) {
  EXPECT_EQ(Bytes(SpecRead().adu()), Adu(kReadPdu));
  // 6.4: read input register 9 (address 0x0008, count 1).
  EXPECT_EQ(Bytes(ReadRegistersRequest(0x1501, 0x11, RegisterKind::kInput, 0x08, 1).adu()),
            Adu({0x04, 0x00, 0x08, 0x00, 0x01}));
  // 6.6: write register 2 (address 0x0001) = 0x0003.
  EXPECT_EQ(Bytes(WriteRegisterRequest(0x1501, 0x11, 0x0001, 0x0003).adu()),
            Adu({0x06, 0x00, 0x01, 0x00, 0x03}));
  // 6.12: write registers 2..3 = 0x000A, 0x0102.
  const std::array<uint16_t, 2> values = {0x000A, 0x0102};
  EXPECT_EQ(Bytes(WriteRegistersRequest(0x1501, 0x11, 0x0001, values).adu()),
            Adu({0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}));
}

TEST(ModbusTcpFrame, TheSpecificationsRepliesAreAcceptedAndDecoded) {
  const std::vector<uint8_t> reply = Adu(kReadReplyPdu);
  ASSERT_TRUE(CheckReply(SpecRead(), reply).ok());
  std::array<uint16_t, 3> regs{};
  ReplyRegisters(reply, regs);
  EXPECT_EQ(regs, (std::array<uint16_t, 3>{0x022B, 0x0000, 0x0064}));

  EXPECT_TRUE(CheckReply(WriteRegisterRequest(0x1501, 0x11, 0x0001, 0x0003),
                         Adu({0x06, 0x00, 0x01, 0x00, 0x03}))
                  .ok());
  const std::array<uint16_t, 2> values = {0x000A, 0x0102};
  EXPECT_TRUE(CheckReply(WriteRegistersRequest(0x1501, 0x11, 0x0001, values),
                         Adu({0x10, 0x00, 0x01, 0x00, 0x02}))
                  .ok());
}

TEST(ModbusTcpFrame, AnExceptionReplyCarriesItsCode) {
  // 7: exception 02 (illegal data address) to function 03.
  const PlcStatus s = CheckReply(SpecRead(), Adu({0x83, 0x02}));
  EXPECT_EQ(s.kind, PlcErrorKind::kException);
  EXPECT_EQ(s.exception_code, 2);
  EXPECT_EQ(s.reply_fault, ReplyFault::kNone);
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x83, 0x02, 0x00})), ReplyFault::kLength)
      << "an exception PDU is two bytes";
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x83, 0x00})), ReplyFault::kFunction) << "no exception 0";
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x83, 0x0C})), ReplyFault::kFunction) << "no exception 12";
  EXPECT_EQ(CheckReply(SpecRead(), Adu({0x83, 0x0B})).exception_code, 11)
      << "gateway target device failed to respond";
}

TEST(ModbusTcpFrame, EachWrongHeaderFieldIsNamed) {
  EXPECT_EQ(FaultOf(SpecRead(), Adu(kReadReplyPdu, 0x1500)), ReplyFault::kTransactionId);
  EXPECT_EQ(FaultOf(SpecRead(), Adu(kReadReplyPdu, 0x1501, 0x12)), ReplyFault::kUnitId);
  std::vector<uint8_t> protocol = Adu(kReadReplyPdu);
  protocol[3] = 0x01;  // protocol id 0x0001, which libmodbus 3.1.6 lets through
  EXPECT_EQ(FaultOf(SpecRead(), protocol), ReplyFault::kProtocolId);
  protocol[2] = 0x01;
  protocol[3] = 0x00;
  EXPECT_EQ(FaultOf(SpecRead(), protocol), ReplyFault::kProtocolId);

  std::vector<uint8_t> longer = Adu(kReadReplyPdu);
  longer[5] += 1;  // announces a byte that is not there
  EXPECT_EQ(FaultOf(SpecRead(), longer), ReplyFault::kLength);
  std::vector<uint8_t> shorter = Adu(kReadReplyPdu);
  shorter[5] -= 1;
  shorter.pop_back();  // framed by the MBAP length: the PDU is one byte short of its byte count
  EXPECT_EQ(FaultOf(SpecRead(), shorter), ReplyFault::kLength);
}

TEST(ModbusTcpFrame, TheHeaderAloneFramesTheReplyOrIsRefused) {
  const std::vector<uint8_t> reply = Adu(kReadReplyPdu);
  const HeaderCheck ok = CheckReplyHeader(std::span(reply).first(kMbapHeaderBytes));
  EXPECT_EQ(ok.fault, ReplyFault::kNone);
  EXPECT_EQ(ok.pdu_bytes, kReadReplyPdu.size());
  for (const int length : {0, 1, 255, 65535}) {
    std::vector<uint8_t> header(reply.begin(), reply.begin() + kMbapHeaderBytes);
    header[4] = static_cast<uint8_t>(length >> 8);
    header[5] = static_cast<uint8_t>(length & 0xff);
    EXPECT_EQ(CheckReplyHeader(header).fault, ReplyFault::kLength) << "MBAP length " << length;
  }
  std::vector<uint8_t> largest(reply.begin(), reply.begin() + kMbapHeaderBytes);
  largest[4] = 0;
  largest[5] = 254;
  EXPECT_EQ(CheckReplyHeader(largest).pdu_bytes, kMaxPduBytes);
}

TEST(ModbusTcpFrame, APduThatAnswersAnotherQuestionIsNamed) {
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x04, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64})),
            ReplyFault::kFunction);
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x03, 0x04, 0x02, 0x2B, 0x00, 0x00})), ReplyFault::kByteCount)
      << "two registers where three were asked";
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00})),
            ReplyFault::kLength)
      << "a byte count of 6 with 5 data bytes";
  EXPECT_EQ(FaultOf(WriteRegisterRequest(0x1501, 0x11, 0x0001, 0x0003),
                    Adu({0x06, 0x00, 0x01, 0x00, 0x04})),
            ReplyFault::kEcho);
  EXPECT_EQ(FaultOf(WriteRegisterRequest(0x1501, 0x11, 0x0001, 0x0003),
                    Adu({0x06, 0x00, 0x02, 0x00, 0x03})),
            ReplyFault::kEcho);
  const std::array<uint16_t, 2> values = {0x000A, 0x0102};
  EXPECT_EQ(FaultOf(WriteRegistersRequest(0x1501, 0x11, 0x0001, values),
                    Adu({0x10, 0x00, 0x01, 0x00, 0x03})),
            ReplyFault::kEcho);
  EXPECT_EQ(
      FaultOf(WriteRegistersRequest(0x1501, 0x11, 0x0001, values), Adu({0x10, 0x00, 0x01, 0x00})),
      ReplyFault::kLength);
  EXPECT_EQ(FaultOf(SpecRead(), Adu({})), ReplyFault::kLength) << "no PDU at all";
  EXPECT_EQ(FaultOf(SpecRead(), Adu({0x03})), ReplyFault::kLength) << "a function and no data";
}

}  // namespace
}  // namespace canalid::drivers
