#include "drivers/modbus/modbus_errors.h"

#include <modbus/modbus.h>

#include <cerrno>

namespace canalid::drivers {

PlcStatus TranslateModbusErrno(int errnum) {
  PlcStatus status;
  status.sys_errno = errnum;
  if (errnum == 0) return status;
  if (errnum >= EMBXILFUN && errnum <= EMBXGTAR) {
    status.kind = PlcErrorKind::kException;
    status.exception_code = errnum - MODBUS_ENOBASE;
    return status;
  }
  switch (errnum) {
    case EMBBADCRC:
    case EMBBADDATA:
    case EMBBADEXC:
    case EMBUNKEXC:
    case EMBBADSLAVE:
      status.kind = PlcErrorKind::kBadData;
      return status;
    case EMBMDATA:
    case EINVAL:
    case EACCES:
    case EPERM:
    case ENOMEM:
      status.kind = PlcErrorKind::kConfig;
      return status;
    case ETIMEDOUT:
      status.kind = PlcErrorKind::kTimeout;
      return status;
    default:
      // Resets, refusals, EOF and unknown errors: the link state is unknown, so the safe reading
      // is "disconnected", which makes the poller reconnect.
      status.kind = PlcErrorKind::kDisconnected;
      return status;
  }
}

const char* PlcErrorKindName(PlcErrorKind kind) {
  switch (kind) {
    case PlcErrorKind::kNone:
      return "ok";
    case PlcErrorKind::kTimeout:
      return "timeout";
    case PlcErrorKind::kException:
      return "modbus exception";
    case PlcErrorKind::kDisconnected:
      return "disconnected";
    case PlcErrorKind::kBadData:
      return "bad data";
    case PlcErrorKind::kConfig:
      return "config";
  }
  return "unknown";
}

const char* ReplyFaultName(ReplyFault fault) {
  switch (fault) {
    case ReplyFault::kNone:
      return "none";
    case ReplyFault::kTransactionId:
      return "transaction_id";
    case ReplyFault::kProtocolId:
      return "protocol_id";
    case ReplyFault::kLength:
      return "length";
    case ReplyFault::kUnitId:
      return "unit_id";
    case ReplyFault::kFunction:
      return "function";
    case ReplyFault::kByteCount:
      return "byte_count";
    case ReplyFault::kEcho:
      return "echo";
    case ReplyFault::kTruncated:
      return "truncated";
  }
  return "unknown";
}

}  // namespace canalid::drivers
