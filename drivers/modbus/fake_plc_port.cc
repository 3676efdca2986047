#include "drivers/modbus/fake_plc_port.h"

#include <algorithm>

namespace canalid::drivers {
namespace {

PlcStatus Status(PlcErrorKind kind) {
  PlcStatus s;
  s.kind = kind;
  return s;
}

}  // namespace

FakePlcPort::FakePlcPort() : holding_(65536, 0), input_(65536, 0) {}

PlcStatus FakePlcPort::Connect() noexcept {
  std::lock_guard lock(mutex_);
  ++connects_;
  connected_ = connect_result_.ok();
  return connect_result_;
}

void FakePlcPort::Close() noexcept {
  std::lock_guard lock(mutex_);
  connected_ = false;
}

bool FakePlcPort::connected() const noexcept {
  std::lock_guard lock(mutex_);
  return connected_;
}

PlcStatus FakePlcPort::TakeFailure() {
  if (!connected_) return Status(PlcErrorKind::kDisconnected);
  if (failures_.empty()) return PlcStatus::Ok();
  const PlcStatus s = failures_.front();
  failures_.pop_front();
  // Behave like the real port: a lost link stays lost until the next Connect().
  if (s.kind == PlcErrorKind::kDisconnected) connected_ = false;
  return s;
}

PlcStatus FakePlcPort::ReadRegisters(RegisterKind kind, int address,
                                     std::span<uint16_t> out) noexcept {
  std::lock_guard lock(mutex_);
  const int count = static_cast<int>(out.size());
  if (count < 1 || count > kMaxReadRegisters || address < 0 || address + count > 65536) {
    return Status(PlcErrorKind::kConfig);
  }
  const PlcStatus s = TakeFailure();
  if (!s.ok()) return s;
  ++reads_;
  const auto& table = kind == RegisterKind::kHolding ? holding_ : input_;
  std::copy_n(table.begin() + address, count, out.begin());
  return s;
}

PlcStatus FakePlcPort::WriteRegister(int address, uint16_t value) noexcept {
  const uint16_t one[1] = {value};
  return WriteRegisters(address, one);
}

PlcStatus FakePlcPort::WriteRegisters(int address, std::span<const uint16_t> values) noexcept {
  std::lock_guard lock(mutex_);
  const int count = static_cast<int>(values.size());
  if (count < 1 || count > kMaxWriteRegisters || address < 0 || address + count > 65536) {
    return Status(PlcErrorKind::kConfig);
  }
  const PlcStatus s = TakeFailure();
  if (!s.ok()) return s;
  ++writes_;
  std::copy(values.begin(), values.end(), holding_.begin() + address);
  return s;
}

void FakePlcPort::SetRegister(RegisterKind kind, int address, uint16_t value) {
  std::lock_guard lock(mutex_);
  (kind == RegisterKind::kHolding ? holding_ : input_).at(static_cast<std::size_t>(address)) =
      value;
}

uint16_t FakePlcPort::GetRegister(RegisterKind kind, int address) const {
  std::lock_guard lock(mutex_);
  return (kind == RegisterKind::kHolding ? holding_ : input_).at(static_cast<std::size_t>(address));
}

void FakePlcPort::FailNextRequest(const PlcStatus& status) {
  std::lock_guard lock(mutex_);
  failures_.push_back(status);
}

void FakePlcPort::SetConnectResult(const PlcStatus& status) {
  std::lock_guard lock(mutex_);
  connect_result_ = status;
}

int FakePlcPort::reads() const {
  std::lock_guard lock(mutex_);
  return reads_;
}

int FakePlcPort::writes() const {
  std::lock_guard lock(mutex_);
  return writes_;
}

int FakePlcPort::connects() const {
  std::lock_guard lock(mutex_);
  return connects_;
}

}  // namespace canalid::drivers
