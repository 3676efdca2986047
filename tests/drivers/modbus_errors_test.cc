#include "drivers/modbus/modbus_errors.h"

#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <cerrno>

namespace canalid::drivers {
namespace {

// The exception codes are those of the Modbus application protocol spec (section 7), written
// here as numbers rather than taken from libmodbus's own macros.
TEST(ModbusErrors, ExceptionRepliesKeepTheirCode) {
  const struct {
    int errnum;
    int code;
  } cases[] = {{EMBXILFUN, 1}, {EMBXILADD, 2}, {EMBXILVAL, 3},  {EMBXSFAIL, 4},  {EMBXACK, 5},
               {EMBXSBUSY, 6}, {EMBXNACK, 7},  {EMBXMEMPAR, 8}, {EMBXGPATH, 10}, {EMBXGTAR, 11}};
  for (const auto& c : cases) {
    const PlcStatus s = TranslateModbusErrno(c.errnum);
    EXPECT_EQ(s.kind, PlcErrorKind::kException) << c.errnum;
    EXPECT_EQ(s.exception_code, c.code) << c.errnum;
    EXPECT_EQ(s.sys_errno, c.errnum);
  }
}

TEST(ModbusErrors, LinkAndDataErrorsAreTyped) {
  EXPECT_EQ(TranslateModbusErrno(0).kind, PlcErrorKind::kNone);
  EXPECT_EQ(TranslateModbusErrno(ETIMEDOUT).kind, PlcErrorKind::kTimeout);
  for (int e : {ECONNRESET, EPIPE, ECONNREFUSED, ENOTCONN, EBADF, EIO, ENOENT}) {
    EXPECT_EQ(TranslateModbusErrno(e).kind, PlcErrorKind::kDisconnected) << e;
  }
  for (int e : {EMBBADCRC, EMBBADDATA, EMBBADEXC, EMBUNKEXC, EMBBADSLAVE}) {
    EXPECT_EQ(TranslateModbusErrno(e).kind, PlcErrorKind::kBadData) << e;
    EXPECT_EQ(TranslateModbusErrno(e).exception_code, 0);
  }
  for (int e : {EMBMDATA, EINVAL, EACCES}) {
    EXPECT_EQ(TranslateModbusErrno(e).kind, PlcErrorKind::kConfig) << e;
  }
  // Unknown errors must make the poller reconnect rather than be ignored.
  EXPECT_EQ(TranslateModbusErrno(123456).kind, PlcErrorKind::kDisconnected);
}

TEST(ModbusErrors, NamesAreDistinct) {
  EXPECT_STREQ(PlcErrorKindName(PlcErrorKind::kTimeout), "timeout");
  EXPECT_STREQ(PlcErrorKindName(PlcErrorKind::kException), "modbus exception");
  EXPECT_STREQ(PlcErrorKindName(PlcErrorKind::kDisconnected), "disconnected");
}

}  // namespace
}  // namespace canalid::drivers
