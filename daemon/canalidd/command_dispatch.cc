#include "daemon/canalidd/command_dispatch.h"

#include <algorithm>
#include <string>

#include "daemon/canalidd/clock.h"
#include "daemon/canalidd/key_file.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/log.h"

namespace canalid::daemon {

CommandDispatch::CommandDispatch(const DaemonPlan& plan, drivers::Bus& bus, Handler on_command)
    : plan_(plan), bus_(bus), on_command_(std::move(on_command)) {}

void CommandDispatch::Start(StateStore* store) {
  if (!plan_.commands_enabled) return;
  store_ = store;
  drivers::CommandAuthOptions options;
  options.enabled = true;
  options.max_clock_skew_s = plan_.command_max_clock_skew_s;
  {
    const drivers::SecretBytes key = ReadKeyFile(plan_.command_key_file);  // wiped at the brace
    authenticator_ = std::make_unique<drivers::CommandAuthenticator>(options, key.span());
  }
  if (store_) {
    std::string problem;
    const int64_t now_us = ToUtime(WallNowS());
    for (const auto& [sender, counter] : store_->LoadCommandCounters(&problem)) {
      if (!authenticator_->RestoreCounter(sender, counter, now_us)) {
        LogWarning("state: command counter " + std::to_string(counter) + " of sender '" + sender +
                   "' is out of range (<= 0, or ahead of the clock by more than "
                   "max_clock_skew_s); ignored");
      }
    }
    if (!problem.empty()) LogWarning("state: " + problem);
  }
  receiver_ = std::make_unique<drivers::CommandReceiver>(
      bus_, plan_.channel_prefix + "COMMAND", *authenticator_, [] { return ToUtime(WallNowS()); },
      [this](const drivers::AcceptedCommand& command) { OnAccepted(command); });
  LogInfo("commands enabled on " + plan_.channel_prefix + "COMMAND");
}

void CommandDispatch::OnAccepted(const drivers::AcceptedCommand& command) {
  if (std::find(plan_.command_kinds.begin(), plan_.command_kinds.end(), command.kind) ==
      plan_.command_kinds.end()) {
    LogWarning("command from " + command.sender +
               " refused: this kind is not accepted by the configuration");
    return;
  }
  if (store_) {
    try {
      store_->SaveCommandCounters(authenticator_->last_counters());
    } catch (const std::exception& e) {
      LogError(std::string("state: ") + e.what());
    }
  }
  on_command_(command);
}

void CommandDispatch::LogRejected(bool flush) {
  if (!receiver_) return;
  const double now = SteadyNowS();
  for (int v = 1; v < drivers::kNumCommandVerdicts; ++v) {
    const auto verdict = static_cast<drivers::CommandVerdict>(v);
    const auto index = static_cast<std::size_t>(v);
    const int64_t count = receiver_->count(verdict);
    const int64_t unlogged = count - verdicts_logged_[index];
    if (unlogged == 0) continue;
    // At most one line a second per verdict (the first at once), with the count: a flood of bad
    // messages must not flood the journal or block the loop on a slow log.
    if (!flush && now - verdict_logged_at_s_[index] < 1.0) continue;
    LogWarning(std::string("command rejected (") + drivers::CommandVerdictName(verdict) + ")" +
               (unlogged > 1 ? " x" + std::to_string(unlogged) : std::string()));
    verdicts_logged_[index] = count;
    verdict_logged_at_s_[index] = now;
  }
}

}  // namespace canalid::daemon
