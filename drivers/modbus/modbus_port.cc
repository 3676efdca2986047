#include "drivers/modbus/modbus_port.h"

#include <modbus/modbus.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/types.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers/modbus/modbus_errors.h"

namespace canalid::drivers {
namespace {

void CheckRange(const char* what, double value, double low, double high) {
  if (!(value >= low && value <= high)) {
    throw std::invalid_argument(std::string("modbus: ") + what + " = " + std::to_string(value) +
                                " outside [" + std::to_string(low) + ", " + std::to_string(high) +
                                "]");
  }
}

void CheckTimeout(const char* what, double seconds) {
  if (!(seconds > 0.0 && seconds <= 60.0)) {
    throw std::invalid_argument(std::string("modbus: ") + what + " = " + std::to_string(seconds) +
                                " s outside (0, 60]");
  }
}

// libmodbus takes timeouts as (seconds, microseconds) with microseconds < 1e6.
void SetTimeout(modbus_t* ctx, double seconds, bool byte_timeout) {
  const auto total_us = static_cast<uint64_t>(std::llround(seconds * 1e6));
  const auto sec = static_cast<uint32_t>(total_us / 1000000);
  const auto usec = static_cast<uint32_t>(total_us % 1000000);
  if (byte_timeout) {
    modbus_set_byte_timeout(ctx, sec, usec);
  } else {
    modbus_set_response_timeout(ctx, sec, usec);
  }
}

PlcStatus ConfigError(int errnum) {
  PlcStatus s;
  s.kind = PlcErrorKind::kConfig;
  s.sys_errno = errnum;
  return s;
}

using Clock = std::chrono::steady_clock;

enum class Io { kDone, kTimeout, kClosed, kError };

// Waits until `fd` is ready for `events` or the deadline passes; kError carries errno in `err`.
Io WaitReady(int fd, short events, Clock::time_point deadline, int& err) {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return Io::kTimeout;
    pollfd p{fd, events, 0};
    const int rc = poll(&p, 1, static_cast<int>(left.count()));
    if (rc > 0) return Io::kDone;  // readable, writable, or an error that send/recv will report
    if (rc == 0) return Io::kTimeout;
    if (errno != EINTR) {
      err = errno;
      return Io::kError;
    }
  }
}

Io SendAll(int fd, std::span<const uint8_t> bytes, Clock::time_point deadline, int& err) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n =
        send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      err = errno;
      return Io::kError;
    }
    const Io ready = WaitReady(fd, POLLOUT, deadline, err);
    if (ready != Io::kDone) return ready;
  }
  return Io::kDone;
}

// Reads exactly bytes.size() bytes; `got` counts those that arrived, whatever the outcome.
Io ReceiveExactly(int fd, std::span<uint8_t> bytes, Clock::time_point deadline, std::size_t& got,
                  int& err) {
  got = 0;
  while (got < bytes.size()) {
    const ssize_t n = recv(fd, bytes.data() + got, bytes.size() - got, MSG_DONTWAIT);
    if (n > 0) {
      got += static_cast<std::size_t>(n);
      continue;
    }
    if (n == 0) return Io::kClosed;
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      err = errno;
      return Io::kError;
    }
    const Io ready = WaitReady(fd, POLLIN, deadline, err);
    if (ready != Io::kDone) return ready;
  }
  return Io::kDone;
}

}  // namespace

void ValidateModbusConfig(const ModbusTcpConfig& c) {
  if (c.host.empty()) throw std::invalid_argument("modbus: host is empty");
  CheckRange("port", c.port, 1, 65535);
  CheckRange("unit_id", c.unit_id, 0, 255);
  CheckTimeout("response_timeout_s", c.response_timeout_s);
  CheckTimeout("connect_timeout_s", c.connect_timeout_s);
}

void ValidateModbusConfig(const ModbusRtuConfig& c) {
  if (c.device.empty()) throw std::invalid_argument("modbus: device is empty");
  CheckRange("baud", c.baud, 1, 4000000);
  if (c.parity != 'N' && c.parity != 'E' && c.parity != 'O') {
    throw std::invalid_argument(std::string("modbus: parity = '") + c.parity +
                                "' is not one of 'N', 'E', 'O'");
  }
  CheckRange("data_bits", c.data_bits, 5, 8);
  CheckRange("stop_bits", c.stop_bits, 1, 2);
  CheckRange("unit_id", c.unit_id, 1, 247);
  CheckTimeout("response_timeout_s", c.response_timeout_s);
}

ModbusPort::ModbusPort(const ModbusTcpConfig& config)
    : config_(config), unit_id_(config.unit_id), response_timeout_s_(config.response_timeout_s) {
  ValidateModbusConfig(config);
}

ModbusPort::ModbusPort(const ModbusRtuConfig& config)
    : config_(config), unit_id_(config.unit_id), response_timeout_s_(config.response_timeout_s) {
  ValidateModbusConfig(config);
}

ModbusPort::~ModbusPort() {
  Close();
  if (ctx_ != nullptr) modbus_free(ctx_);
}

double ModbusPort::response_timeout_s() const noexcept { return response_timeout_s_; }

PlcStatus ModbusPort::CreateContext() noexcept {
  if (const auto* tcp = std::get_if<ModbusTcpConfig>(&config_)) {
    const std::string service = std::to_string(tcp->port);
    ctx_ = modbus_new_tcp_pi(tcp->host.c_str(), service.c_str());
  } else if (const auto* rtu = std::get_if<ModbusRtuConfig>(&config_)) {
    ctx_ =
        modbus_new_rtu(rtu->device.c_str(), rtu->baud, rtu->parity, rtu->data_bits, rtu->stop_bits);
  }
  if (ctx_ == nullptr) return ConfigError(errno);
  if (modbus_set_slave(ctx_, unit_id_) != 0) return ConfigError(errno);
  return PlcStatus::Ok();
}

PlcStatus ModbusPort::Connect() noexcept {
  if (connected_) return PlcStatus::Ok();
  if (ctx_ == nullptr) {
    const PlcStatus created = CreateContext();
    if (!created.ok()) {
      if (ctx_ != nullptr) modbus_free(ctx_);
      ctx_ = nullptr;
      return created;
    }
  }
  // libmodbus bounds a TCP connect by the response timeout, so it is set to the connect timeout
  // for the connect and back afterwards.
  if (const auto* tcp = std::get_if<ModbusTcpConfig>(&config_)) {
    SetTimeout(ctx_, tcp->connect_timeout_s, false);
  }
  const int rc = modbus_connect(ctx_);
  const int connect_errno = errno;
  const double response = response_timeout_s();
  SetTimeout(ctx_, response, false);
  SetTimeout(ctx_, response, true);
  if (rc != 0) {
    // A refused or unreachable peer is a link problem (retry), never a config one.
    PlcStatus s = TranslateModbusErrno(connect_errno);
    if (s.kind != PlcErrorKind::kTimeout) s.kind = PlcErrorKind::kDisconnected;
    return s;
  }
  connected_ = true;
  return PlcStatus::Ok();
}

void ModbusPort::Close() noexcept {
  if (ctx_ != nullptr && connected_) modbus_close(ctx_);
  connected_ = false;
}

PlcStatus ModbusPort::Failed() noexcept {
  PlcStatus s = TranslateModbusErrno(errno);
  // A failure without errno leaves the link state unknown: treat it as lost.
  if (s.ok()) s.kind = PlcErrorKind::kDisconnected;
  if (s.kind == PlcErrorKind::kDisconnected) {
    Close();
  } else if (s.kind == PlcErrorKind::kTimeout || s.kind == PlcErrorKind::kBadData) {
    modbus_flush(ctx_);
  }
  return s;
}

PlcStatus ModbusPort::TcpExchange(const TcpRequest& request) noexcept {
  const int fd = modbus_get_socket(ctx_);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(response_timeout_s_));
  int err = 0;
  // Every return below leaves the stream at a frame boundary or drops the link, so nothing is
  // flushed: a flush could eat the first half of a late reply and lose the framing after it.
  auto lost = [this](PlcStatus s) {
    s.kind = PlcErrorKind::kDisconnected;
    Close();
    return s;
  };
  // A request only partly sent leaves the PLC mid-frame: the stream cannot be trusted any more.
  if (const Io sent = SendAll(fd, request.adu(), deadline, err); sent != Io::kDone) {
    return lost(sent == Io::kError ? TranslateModbusErrno(err) : PlcStatus{});
  }
  // Frames are read one after the other until this request's. A whole frame answering one of the
  // last kMaxLateReplies requests (a reply that came after its request timed out) is skipped, so
  // one late reply does not put every later exchange one reply behind; at most that many are
  // skipped, and never past the deadline.
  constexpr int kMaxLateReplies = 8;
  const auto skipped_fault = [](int skipped) {
    return skipped > 0 ? ReplyFault::kTransactionId : ReplyFault::kNone;
  };
  int skipped = 0;
  for (;; ++skipped) {
    if (skipped > kMaxLateReplies) {
      return lost(PlcStatus{PlcErrorKind::kDisconnected, 0, 0, ReplyFault::kTransactionId});
    }
    reply_size_ = 0;
    std::size_t got = 0;
    Io io = Clock::now() < deadline || skipped == 0
                ? ReceiveExactly(fd, std::span<uint8_t>(reply_.data(), kMbapHeaderBytes), deadline,
                                 got, err)
                : Io::kTimeout;
    reply_size_ = got;
    if (io == Io::kDone) {
      const HeaderCheck header = CheckReplyHeader(std::span(reply_.data(), kMbapHeaderBytes));
      // No length to find the frame's end by: the stream is lost.
      if (header.fault != ReplyFault::kNone) return lost(PlcStatus{{}, 0, 0, header.fault});
      io =
          ReceiveExactly(fd, std::span<uint8_t>(reply_.data() + kMbapHeaderBytes, header.pdu_bytes),
                         deadline, got, err);
      reply_size_ += got;
    }
    switch (io) {
      case Io::kDone:
        break;
      case Io::kTimeout:
        // A frame cut short: its rest may come later, in the middle of the next reply.
        if (reply_size_ > 0) return lost(PlcStatus{{}, 0, ETIMEDOUT, ReplyFault::kTruncated});
        return PlcStatus{PlcErrorKind::kTimeout, 0, ETIMEDOUT, skipped_fault(skipped)};
      case Io::kClosed:
        return lost(PlcStatus{{}, 0, ECONNRESET, skipped_fault(skipped)});
      case Io::kError: {
        PlcStatus s = TranslateModbusErrno(err);
        s.reply_fault = skipped_fault(skipped);
        return lost(s);
      }
    }
    const auto id = static_cast<uint16_t>(reply_[0] << 8 | reply_[1]);
    const auto age = static_cast<uint16_t>(request.transaction_id - id);
    if (age == 0) break;
    // Not one of the last requests': no late reply, another transaction's (or a forged) frame.
    if (age > kMaxLateReplies)
      return PlcStatus{PlcErrorKind::kBadData, 0, 0, ReplyFault::kTransactionId};
  }
  PlcStatus s = CheckReply(request, std::span(reply_.data(), reply_size_));
  // A PDU whose length does not fit its function: the MBAP length that framed it is wrong, so
  // the next frame may start elsewhere (a tail still to come).
  if (s.kind == PlcErrorKind::kBadData && s.reply_fault == ReplyFault::kLength) return lost(s);
  // An answer after a skipped late reply still counts it (ReplyFault on a good status).
  if (s.reply_fault == ReplyFault::kNone) s.reply_fault = skipped_fault(skipped);
  return s;
}

PlcStatus ModbusPort::ReadRegisters(RegisterKind kind, int address,
                                    std::span<uint16_t> out) noexcept {
  const int count = static_cast<int>(out.size());
  if (count < 1 || count > kMaxReadRegisters || address < 0 || address + count > 65536) {
    return ConfigError(EINVAL);
  }
  if (!connected_) return TranslateModbusErrno(ENOTCONN);
  if (tcp()) {
    const PlcStatus s = TcpExchange(
        ReadRegistersRequest(next_transaction_id_++, static_cast<uint8_t>(unit_id_), kind,
                             static_cast<uint16_t>(address), static_cast<uint16_t>(count)));
    if (s.ok()) ReplyRegisters(std::span(reply_.data(), reply_size_), out);
    return s;
  }
  errno = 0;
  const int rc = kind == RegisterKind::kHolding
                     ? modbus_read_registers(ctx_, address, count, out.data())
                     : modbus_read_input_registers(ctx_, address, count, out.data());
  if (rc < 0) return Failed();
  if (rc != count) {
    PlcStatus s;
    s.kind = PlcErrorKind::kBadData;
    return s;
  }
  return PlcStatus::Ok();
}

PlcStatus ModbusPort::WriteRegister(int address, uint16_t value) noexcept {
  if (address < 0 || address > 65535) return ConfigError(EINVAL);
  if (!connected_) return TranslateModbusErrno(ENOTCONN);
  if (tcp()) {
    return TcpExchange(WriteRegisterRequest(next_transaction_id_++, static_cast<uint8_t>(unit_id_),
                                            static_cast<uint16_t>(address), value));
  }
  errno = 0;
  if (modbus_write_register(ctx_, address, value) != 1) return Failed();
  return PlcStatus::Ok();
}

PlcStatus ModbusPort::WriteRegisters(int address, std::span<const uint16_t> values) noexcept {
  const int count = static_cast<int>(values.size());
  if (count < 1 || count > kMaxWriteRegisters || address < 0 || address + count > 65536) {
    return ConfigError(EINVAL);
  }
  if (!connected_) return TranslateModbusErrno(ENOTCONN);
  if (tcp()) {
    return TcpExchange(WriteRegistersRequest(next_transaction_id_++, static_cast<uint8_t>(unit_id_),
                                             static_cast<uint16_t>(address), values));
  }
  errno = 0;
  if (modbus_write_registers(ctx_, address, count, values.data()) != count) return Failed();
  return PlcStatus::Ok();
}

}  // namespace canalid::drivers
