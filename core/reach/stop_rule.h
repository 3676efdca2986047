#pragma once
#include <cstdint>

namespace canalid::core {

/// Where a stopping program stands with its actuators.
enum class StopProgress : std::uint8_t {
  kWait,            ///< a reach's nominal is not confirmed yet and there is time left: wait
  kSafe,            ///< every reach's nominal is confirmed by the PLC: stop
  kDeadlinePassed,  ///< still unconfirmed at the deadline: stop, and say so as an error
};

/// A stop first aborts every experiment (restoring the nominals), then waits for the PLC to
/// confirm every restore (ReachController::restore_pending()), at most until `deadline_s` (the
/// stop's start plus its timeout, on the same clock as `now_s`). Pure.
inline StopProgress DecideStop(bool any_restore_pending, double now_s, double deadline_s) {
  if (!any_restore_pending) return StopProgress::kSafe;
  return now_s < deadline_s ? StopProgress::kWait : StopProgress::kDeadlinePassed;
}

}  // namespace canalid::core
