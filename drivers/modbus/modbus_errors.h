#pragma once
#include "drivers/modbus/plc_port.h"

namespace canalid::drivers {

/// The one place libmodbus errno values become PlcStatus:
///   EMBXILFUN..EMBXGTAR (Modbus exceptions 1..11)         -> kException, exception_code 1..11
///   EMBBADCRC, EMBBADDATA, EMBBADEXC, EMBUNKEXC, EMBBADSLAVE -> kBadData (reply does not match)
///   EMBMDATA (too many registers requested), EINVAL, EACCES, EPERM, ENOMEM -> kConfig
///   ETIMEDOUT                                              -> kTimeout
///   ECONNRESET, EPIPE, ECONNREFUSED, ENOTCONN, ECONNABORTED, EBADF, EHOSTUNREACH, ENETUNREACH,
///   ENETDOWN, EIO, ENOENT, ENODEV, ENXIO and anything else -> kDisconnected (reconnect and retry)
/// `errnum` 0 gives kNone. Pure.
PlcStatus TranslateModbusErrno(int errnum);

}  // namespace canalid::drivers
