#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>

#include "daemon/canalidd/daemon_plan.h"
#include "daemon/canalidd/state_store.h"
#include "drivers/auth/command_auth.h"
#include "drivers/lcm/bus.h"
#include "drivers/lcm/command_receiver.h"

namespace canalid::daemon {

/// The authenticated commands of `<prefix>COMMAND` (off unless the plan enables them): reads the
/// key file and the saved counters at start, lets the kinds the configuration accepts through to
/// `on_command` after saving the counters (so a restart does not reopen a replay window), and
/// logs the rejected ones at a bounded rate.  Runs on the Asio loop.
class CommandDispatch final {
 public:
  using Handler = std::function<void(const drivers::AcceptedCommand&)>;
  /// `plan` and `bus` outlive the dispatch.
  CommandDispatch(const DaemonPlan& plan, drivers::Bus& bus, Handler on_command);
  /// Subscribes when commands are enabled (else nothing).  `store`: nullptr without a state
  /// directory.  @throws what ReadKeyFile throws (start-up).
  void Start(StateStore* store);
  /// Logs the commands rejected since the last line, per verdict: at once for the first, then at
  /// most once a second with a count (" xN"), every pending count when `flush` (an operator's
  /// audit trail that a flood cannot turn into a journal flood).
  void LogRejected(bool flush);
  /// nullptr when commands are disabled.
  const drivers::CommandReceiver* receiver() const { return receiver_.get(); }

 private:
  void OnAccepted(const drivers::AcceptedCommand& command);

  const DaemonPlan& plan_;
  drivers::Bus& bus_;
  Handler on_command_;
  StateStore* store_ = nullptr;
  std::unique_ptr<drivers::CommandAuthenticator> authenticator_;
  std::unique_ptr<drivers::CommandReceiver> receiver_;
  std::array<int64_t, drivers::kNumCommandVerdicts> verdicts_logged_{};
  std::array<double, drivers::kNumCommandVerdicts> verdict_logged_at_s_{};  ///< steady s, 0: never
};

}  // namespace canalid::daemon
