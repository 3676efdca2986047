#pragma once
#include <cstdint>
#include <deque>
#include <mutex>
#include <vector>

#include "drivers/modbus/plc_port.h"

namespace canalid::drivers {

/// In-memory PlcPort for tests of the code above the port: 65536 holding and 65536 input
/// registers, scripted failures, request counters. Unlike real ports it is thread-safe, so a test
/// thread may change registers while a poller thread reads them.
class FakePlcPort final : public PlcPort {
 public:
  FakePlcPort();

  PlcStatus Connect() noexcept override;
  void Close() noexcept override;
  bool connected() const noexcept override;
  double response_timeout_s() const noexcept override { return 0.0; }
  PlcStatus ReadRegisters(RegisterKind kind, int address,
                          std::span<uint16_t> out) noexcept override;
  PlcStatus WriteRegister(int address, uint16_t value) noexcept override;
  PlcStatus WriteRegisters(int address, std::span<const uint16_t> values) noexcept override;

  void SetRegister(RegisterKind kind, int address, uint16_t value);
  uint16_t GetRegister(RegisterKind kind, int address) const;
  /// The next request (read or write, not connect) fails with `status`; queued in order.
  void FailNextRequest(const PlcStatus& status);
  /// Connect() fails with `status` until cleared with an ok status.
  void SetConnectResult(const PlcStatus& status);
  int reads() const;
  int writes() const;
  int connects() const;

 private:
  PlcStatus TakeFailure();  // with mutex_ held

  mutable std::mutex mutex_;
  std::vector<uint16_t> holding_;
  std::vector<uint16_t> input_;
  std::deque<PlcStatus> failures_;
  PlcStatus connect_result_;
  bool connected_ = false;
  int reads_ = 0;
  int writes_ = 0;
  int connects_ = 0;
};

}  // namespace canalid::drivers
