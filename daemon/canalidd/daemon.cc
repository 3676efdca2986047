#include "daemon/canalidd/daemon.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <sstream>

#include "daemon/canalidd/key_file.h"
#include "daemon/canalidd/log.h"
#include "daemon/canalidd/startup_check.h"
#include "daemon/canalidd/systemd_notify.h"
#include "drivers/json/model_json.h"
#include "drivers/lcm/lcm_bus.h"
#include "drivers/modbus/modbus_port.h"

namespace canalid::daemon {
namespace {

double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double WallNowS() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

// Health counter suffixes as docs/lcm-channels.md names them (PlcErrorKindName is for people).
const char* ReadErrorCounterName(drivers::PlcErrorKind kind) {
  switch (kind) {
    case drivers::PlcErrorKind::kNone:
      return "ok";
    case drivers::PlcErrorKind::kTimeout:
      return "timeout";
    case drivers::PlcErrorKind::kException:
      return "exception";
    case drivers::PlcErrorKind::kDisconnected:
      return "disconnected";
    case drivers::PlcErrorKind::kBadData:
      return "bad_data";
    case drivers::PlcErrorKind::kConfig:
      return "config";
  }
  return "unknown";
}

}  // namespace

struct Daemon::Plc {
  Plc(const PlcWiring& w, boost::asio::io_context& io) : wiring(w), heartbeat_timer(io) {}
  const PlcWiring& wiring;
  std::unique_ptr<drivers::PlcPoller> poller;
  std::vector<std::string> channel_names;
  std::atomic<bool> drain_pending{false};
  boost::asio::steady_timer heartbeat_timer;
  std::uint16_t heartbeat = 0;
  std::vector<int> reaches;
};

struct Daemon::Reach {
  explicit Reach(const ReachWiring& w) : wiring(w), runner(w.runner) {}
  const ReachWiring& wiring;
  core::ReachRunner runner;
  bool restore_pending = false;  // a nominal setpoint not yet confirmed by the PLC
  double restore_target = 0.0;   // the value that restore waits for
  bool guard_on_disk = false;    // <reach>.experiment.json exists (written, or left by a crash)
  bool keep_guard = false;       // a refused start-up: the guard stays for an operator to check
  double last_time_s = 0.0;
  const std::string& name() const { return runner.name(); }
  core::ReachPipeline& pipeline() { return runner.pipeline(); }
  const core::ReachPipeline& pipeline() const { return runner.pipeline(); }
};

Daemon::Daemon(DaemonPlan plan, drivers::Bus& bus, PortFactory make_port, ReloadFunction reload)
    : plan_(std::move(plan)),
      bus_(bus),
      make_port_(std::move(make_port)),
      reload_(std::move(reload)),
      signals_(io_, SIGINT, SIGTERM, SIGHUP),
      health_timer_(io_),
      stop_timer_(io_),
      bus_retry_timer_(io_),
      publisher_(bus_, plan_.channel_prefix) {
  for (std::size_t i = 0; i < plan_.plcs.size(); ++i) {
    auto plc = std::make_unique<Plc>(plan_.plcs[i], io_);
    for (const auto& channel : plan_.plcs[i].poller.channels)
      plc->channel_names.push_back(channel.name);
    Plc* raw = plc.get();
    const int index = static_cast<int>(i);
    // The poller thread only posts a drain; the flag keeps a burst of notifications to one.
    plc->poller = std::make_unique<drivers::PlcPoller>(
        plan_.plcs[i].poller, make_port_(plan_.plcs[i]), [this, raw, index] {
          if (!raw->drain_pending.exchange(true))
            boost::asio::post(io_, [this, index] { Drain(index); });
        });
    plcs_.push_back(std::move(plc));
  }
  for (std::size_t r = 0; r < plan_.reaches.size(); ++r) {
    auto reach = std::make_unique<Reach>(plan_.reaches[r]);
    if (!reach->runner.initial_plan_error().empty())
      LogError("reach " + reach->name() + ": no experiment: " + reach->runner.initial_plan_error());
    plcs_.at(static_cast<std::size_t>(reach->wiring.plc))->reaches.push_back(static_cast<int>(r));
    reaches_.push_back(std::move(reach));
  }
}

Daemon::~Daemon() {
  for (auto& plc : plcs_) plc->poller->Stop();
}

std::unique_ptr<drivers::PlcPort> Daemon::MakeModbusPort(const PlcWiring& wiring) {
  return std::visit(
      [](const auto& link) -> std::unique_ptr<drivers::PlcPort> {
        return std::make_unique<drivers::ModbusPort>(link);
      },
      wiring.link);
}

DaemonExit Daemon::Run() {
  start_steady_s_ = SteadyNowS();
  watchdog_period_s_ = WatchdogPeriodS();
  try {
    publisher_.PublishConfig(plan_.config_path, plan_.config_text, WallNowS());
    LoadState();
    ResumeInterruptedExperiments();
    StartCommands();
    StartSignals();
    StartBusWatch();
    StartHealthTimer();
    StartPollers();
    for (std::size_t i = 0; i < plcs_.size(); ++i) StartHeartbeat(static_cast<int>(i));
  } catch (const std::exception& e) {
    throw StartupError(e.what());  // canalidd exits 78: nothing has run yet
  }
  LogInfo("running: " + std::to_string(plcs_.size()) + " PLC(s), " +
          std::to_string(reaches_.size()) + " reach(es), LCM prefix " + plan_.channel_prefix);
  io_.run();
  for (auto& plc : plcs_) plc->poller->Stop();
  LogInfo(exit_ == DaemonExit::kReload ? "reloading the configuration" : "stopped");
  return exit_;
}

void Daemon::StartPollers() {
  for (auto& plc : plcs_) plc->poller->Start();
}

void Daemon::StartSignals() {
  signals_.async_wait([this](const boost::system::error_code& error, int signal) {
    if (error) return;
    if (signal == SIGHUP) {
      LogInfo("SIGHUP: checking the configuration");
      std::optional<DaemonPlan> plan;
      try {
        plan = reload_ ? reload_() : std::nullopt;
      } catch (const std::exception& e) {
        LogError(std::string("reload failed: ") + e.what());
      }
      if (plan) {
        reloaded_plan_ = std::move(plan);
        NotifyReloading();
        BeginStop(DaemonExit::kReload);
        return;
      }
      LogWarning("the new configuration is not valid; carrying on with the running one");
      StartSignals();
      return;
    }
    LogInfo(signal == SIGTERM ? "SIGTERM: stopping" : "SIGINT: stopping");
    BeginStop(DaemonExit::kStopped);
  });
}

void Daemon::StartBusWatch() {
  lcm_bus_ = dynamic_cast<drivers::LcmBus*>(&bus_);
  if (lcm_bus_ == nullptr) return;  // a fake bus in tests is pumped by the test
  WatchBus();
}

// Watches a duplicate of LCM's descriptor, so Asio never closes LCM's own. LCM's tcpq provider
// may close its socket (hub gone, an unreadable message) and leave fileno -1, or reconnect on its
// own onto another socket: the watched duplicate then no longer names LCM's socket (SameSocket),
// and Handle() with fileno -1 would make liblcm select() on fd -1 and abort (LcmBus::Handle
// refuses that instead).
void Daemon::WatchBus() {
  const int fd = lcm_bus_->fileno();
  const int copy = fd < 0 ? -1 : ::dup(fd);
  if (copy < 0) {
    OnBusLost(fd < 0 ? "no connection (fileno -1)" : std::string("dup: ") + std::strerror(errno));
    return;
  }
  bus_fd_ = std::make_unique<boost::asio::posix::stream_descriptor>(io_, copy);
  WaitForBus();
}

void Daemon::WaitForBus() {
  bus_fd_->async_wait(boost::asio::posix::stream_descriptor::wait_read,
                      [this](const boost::system::error_code& error) {
                        if (error) return;
                        const int handled = bus_.Handle(0.0);
                        LogRejectedCommands(false);
                        if (stopping_) return;
                        if (lcm_bus_->reconnectable()) {
                          const int fd = lcm_bus_->fileno();
                          if (handled < 0 || fd < 0 || !SameSocket(bus_fd_->native_handle(), fd)) {
                            OnBusLost(handled < 0 ? "receive failed" : "connection closed");
                            return;
                          }
                        }
                        WaitForBus();
                      });
}

bool Daemon::SameSocket(int a, int b) {
  struct stat sa {
  }, sb{};
  return ::fstat(a, &sa) == 0 && ::fstat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

void Daemon::OnBusLost(const std::string& why) {
  bus_fd_.reset();
  ++bus_losses_;
  const double delay_s = bus_backoff_s_;
  bus_backoff_s_ = std::min(bus_backoff_s_ * 2.0, kBusBackoffMaxS);
  LogError("LCM bus " + lcm_bus_->url() + " lost (" + why + "); reconnecting in " +
           std::to_string(delay_s) + " s");
  bus_retry_timer_.expires_after(Seconds(delay_s));
  bus_retry_timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || stopping_) return;
    std::string problem;
    if (!lcm_bus_->Reconnect(&problem) || lcm_bus_->fileno() < 0) {
      OnBusLost(problem.empty() ? "no connection (fileno -1)" : problem);
      return;
    }
    ++bus_reconnects_;
    bus_backoff_s_ = kBusBackoffMinS;
    LogInfo("LCM bus " + lcm_bus_->url() + " reconnected");
    WatchBus();
  });
}

void Daemon::StartHealthTimer() {
  health_timer_.expires_after(Seconds(plan_.health_period_s));
  health_timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || stopping_) return;
    LogRejectedCommands(true);
    PublishHealth();
    // The watchdog is fed from the sample loop; with every link down there are no samples, so the
    // health timer keeps systemd informed that the loop itself is alive.
    NotifyWatchdog();
    StartHealthTimer();
  });
}

void Daemon::StartHeartbeat(int index) {
  Plc& plc = *plcs_[static_cast<std::size_t>(index)];
  if (plc.wiring.heartbeat_channel < 0) return;
  plc.heartbeat_timer.expires_after(Seconds(plc.wiring.heartbeat_period_s));
  plc.heartbeat_timer.async_wait([this, index](const boost::system::error_code& error) {
    if (error || stopping_) return;
    Plc& p = *plcs_[static_cast<std::size_t>(index)];
    ++p.heartbeat;
    p.poller->RequestWrite(p.wiring.heartbeat_channel, static_cast<double>(p.heartbeat));
    StartHeartbeat(index);
  });
}

void Daemon::Drain(int index) {
  Plc& plc = *plcs_[static_cast<std::size_t>(index)];
  plc.drain_pending = false;
  plc.poller->DrainSamples([&](const drivers::PollSample& s) { OnPoll(index, s); });
  plc.poller->DrainWriteResults([&](const drivers::WriteResult& r) { OnWriteResult(index, r); });
  // While the poller reconnects no samples arrive, so a running experiment would never hear of
  // the lost link from a sample (after timeouts the link drops without a disconnected poll).
  if (!plc.poller->counters().connected) {
    for (const int r : plc.reaches) {
      Reach& reach = *reaches_[static_cast<std::size_t>(r)];
      Handle(reach, reach.pipeline().OnLinkLost(), reach.last_time_s);
    }
  }
}

void Daemon::OnPoll(int index, const drivers::PollSample& s) {
  Plc& plc = *plcs_[static_cast<std::size_t>(index)];
  publisher_.PublishSample(plc.wiring.poller.plc_name, plc.channel_names, s);
  const bool link_ok = s.status.kind != drivers::PlcErrorKind::kDisconnected;
  if (s.status.ok() && !ready_) {
    ready_ = true;
    NotifyReady();
    LogInfo("PLC " + plc.wiring.poller.plc_name + " answers: ready");
  }
  const double now = SteadyNowS();
  if (watchdog_period_s_ > 0.0 && now - last_watchdog_s_ > watchdog_period_s_ / 4.0) {
    NotifyWatchdog();
    NotifyStatus(Status());
    last_watchdog_s_ = now;
  }
  for (const int r : plc.reaches) {
    Reach& reach = *reaches_[static_cast<std::size_t>(r)];
    const core::ReachReadings readings = core::ReadReach(
        reach.wiring.runner.channels, s.values,
        [&](std::size_t channel) { return s.valid(channel); }, link_ok, s.status.ok(), s.time_s);
    reach.last_time_s = s.time_s;
    const core::ReachPollOutcome outcome = reach.runner.OnPoll(readings);
    if (outcome.nominal_read) {
      LogInfo("reach " + reach.name() + ": nominal setpoint " +
              std::to_string(*outcome.nominal_read) + " (read from the PLC)");
    }
    if (!outcome.plan_error.empty())
      LogError("reach " + reach.name() + ": no experiment: " + outcome.plan_error);
    Handle(reach, outcome.actions, s.time_s);
    if (outcome.actions.online_updated && reach.pipeline().online_id() != nullptr) {
      publisher_.PublishOnlineId(reach.name(), reach.pipeline().online_id()->Snapshot(), s.time_s,
                                 "rls-bank");
    }
    if (reach.restore_pending && link_ok && !outcome.actions.write_setpoint)
      RequestSetpoint(reach, reach.restore_target);
    if (const auto start = reach.runner.StartIfDue(s.status.ok(), !stopping_)) {
      LogInfo("reach " + reach.name() + ": starting the experiment");
      Handle(reach, *start, s.time_s);
    }
  }
}

void Daemon::OnWriteResult(int index, const drivers::WriteResult& result) {
  Plc& plc = *plcs_[static_cast<std::size_t>(index)];
  if (result.channel == plc.wiring.heartbeat_channel) {
    if (result.outcome != drivers::WriteOutcome::kWritten) LogDebug("heartbeat write failed");
    return;
  }
  for (const int r : plc.reaches) {
    Reach& reach = *reaches_[static_cast<std::size_t>(r)];
    if (reach.wiring.runner.channels.actuator != result.channel) continue;
    const bool written = result.outcome == drivers::WriteOutcome::kWritten;
    if (written && reach.restore_pending &&
        std::abs(result.written - reach.restore_target) <=
            1e-9 * (1.0 + std::abs(reach.restore_target))) {
      reach.restore_pending = false;
      LogInfo("reach " + reach.name() + ": nominal setpoint " +
              std::to_string(reach.restore_target) + " restored");
      OnRestoreConfirmed(reach);
    }
    if (!written) {
      LogWarning("reach " + reach.name() + ": setpoint write failed (" +
                 drivers::PlcErrorKindName(result.plc.kind) + ")");
      Handle(reach, reach.pipeline().OnWriteFailed(), reach.last_time_s);
    }
  }
  if (stopping_) FinishStopWhenSafe();
}

void Daemon::RequestSetpoint(Reach& reach, double value) {
  const drivers::WriteTicket ticket =
      plcs_[static_cast<std::size_t>(reach.wiring.plc)]->poller->RequestWrite(
          reach.wiring.runner.channels.actuator, value);
  if (ticket.status != drivers::WriteQueueStatus::kQueued) {
    LogWarning("reach " + reach.name() + ": setpoint write not queued");
  }
}

void Daemon::Handle(Reach& reach, const core::ReachActions& actions, double time_s) {
  const std::string& name = reach.name();
  const int actuator = reach.wiring.runner.channels.actuator;
  if (actions.write_setpoint && actuator >= 0) {
    if (!actions.restore_nominal && !reach.guard_on_disk && !PersistGuard(reach)) {
      // No excitation write without a durable guard: abort instead, which restores the nominal.
      Handle(reach, reach.pipeline().OnGuardNotPersisted(), time_s);
      return;
    }
    if (actions.restore_nominal) {
      reach.restore_pending = true;
      reach.restore_target = *actions.write_setpoint;
    }
    RequestSetpoint(reach, *actions.write_setpoint);
  }
  const auto& plan = reach.pipeline().experiment_plan();
  if (actions.experiment_phase_changed && plan) {
    const core::ExperimentState& state = reach.pipeline().experiment_state();
    publisher_.PublishExperiment(name, state, *plan,
                                 plcs_[static_cast<std::size_t>(reach.wiring.plc)]
                                     ->channel_names[static_cast<std::size_t>(actuator)],
                                 time_s);
    std::string message =
        "reach " + name + ": experiment " + core::ExperimentPhaseName(state.phase);
    if (state.phase == core::ExperimentPhase::kAborted)
      message += " (" + core::AbortReasonText(*plan, state) + ")";
    (state.phase == core::ExperimentPhase::kAborted ? LogWarning(message) : LogInfo(message));
    NotifyStatus(Status());
  }
  if (actions.experiment_record_complete) {
    core::ReachActions after;
    const std::optional<core::IdPipelineResult> result = reach.pipeline().IdentifyRecord(&after);
    const std::string& problem = reach.pipeline().identification_problem();
    if (result) {
      publisher_.PublishBatchId(name, *result, time_s, reach.pipeline().recorded_samples(),
                                !problem.empty());
      nlohmann::json json = drivers::ToJson(*result);
      json["reach"] = name;
      if (problem.empty()) {
        LogInfo("reach " + name + ": identified " + json.dump());
        SaveModel(reach, *result);
      } else {
        // Published (flagged) for the operator to see, never persisted as the reach's model.
        LogWarning("reach " + name + ": identified a model outside the bounds (" + problem +
                   "); not persisted: " + json.dump());
      }
    } else {
      LogWarning("reach " + name + ": the experiment record could not be identified");
    }
    Handle(reach, after, time_s);
  }
}

void Daemon::LoadState() {
  if (plan_.state_directory.empty()) return;
  store_.emplace(plan_.state_directory);
  const StateLoadReport report = store_->LoadAll();
  for (const std::string& problem : report.problems) LogWarning("state: " + problem);
  for (const auto& temp : report.leftover_temp_files) {
    LogWarning("state: " + temp.string() + ": left by an interrupted write; ignored");
  }
  for (const PersistedModel& model : report.models) {
    const auto reach = std::find_if(reaches_.begin(), reaches_.end(),
                                    [&](const auto& r) { return r->name() == model.reach; });
    if (reach == reaches_.end()) continue;
    // Read back like any input: a file edited by hand or written by a build without these checks
    // must not come back as the reach's model.
    const std::string problem = PersistedIdModelProblem(model, (*reach)->pipeline().model_bounds());
    if (!problem.empty()) {
      LogWarning("state: " + store_->PathFor(model.reach, model.model_kind).string() + ": reach " +
                 model.reach + ": " + problem + "; ignored");
      continue;
    }
    publisher_.PublishModelJson(model.reach, model.model, WallNowS());
    LogInfo("reach " + model.reach + ": resumed the persisted " + model.model_kind + " model " +
            model.model.dump());
  }
}

void Daemon::ResumeInterruptedExperiments() {
  for (auto& r : reaches_) {
    Reach& reach = *r;
    const int actuator = reach.wiring.runner.channels.actuator;
    if (actuator < 0) continue;
    const drivers::PollChannel& channel =
        plcs_[static_cast<std::size_t>(reach.wiring.plc)]
            ->wiring.poller.channels[static_cast<std::size_t>(actuator)];
    core::GuardReading reading;
    if (store_) {
      try {
        reading = store_->LoadGuard(reach.name());
      } catch (const std::exception& e) {
        reading.kind = core::GuardReading::Kind::kCorrupt;
        reading.problem = e.what();
      }
    }
    if (reading.kind == core::GuardReading::Kind::kNone) continue;
    core::RestartContext context;
    context.reach = reach.name();
    context.actuator = channel.name;
    context.setpoint_min = channel.limits.min_value;
    context.setpoint_max = channel.limits.max_value;
    context.configured_nominal = reach.wiring.runner.nominal_setpoint;
    const core::RestartDecision decision = core::DecideRestart(context, reading);
    (decision.error ? LogError : LogWarning)(decision.message);
    const std::string plan_error = reach.runner.ApplyRestart(decision);
    if (!plan_error.empty()) LogError("reach " + reach.name() + ": no experiment: " + plan_error);
    reach.guard_on_disk = true;
    reach.keep_guard = decision.action == core::RestartDecision::Action::kRefuse;
    // The first write once the PLC answers (OnPoll asks it again until confirmed).
    if (decision.restore_setpoint) {
      reach.restore_pending = true;
      reach.restore_target = *decision.restore_setpoint;
    }
    const bool restore = decision.action == core::RestartDecision::Action::kRestore;
    const std::string reason =
        restore ? std::string(core::kRestartRestoreReason) + " " +
                      std::to_string(*decision.restore_setpoint) + " persisted at " +
                      core::FormatUtcTime(reading.guard.started_utime_us)
                : std::string(core::kRestartRefusedReason) + ": " + decision.message;
    publisher_.PublishRestart(reach.name(), channel.name,
                              decision.restore_setpoint ? *decision.restore_setpoint : std::nan(""),
                              reason, WallNowS());
  }
}

bool Daemon::PersistGuard(Reach& reach) {
  const double nominal = reach.runner.nominal();
  const std::string refused = "reach " + reach.name() + ": experiment guard not persisted";
  if (!store_) {
    LogError(refused + " (no state directory): no excitation, restoring nominal " +
             std::to_string(nominal));
    return false;
  }
  core::ExperimentGuard guard;
  guard.reach = reach.name();
  guard.actuator = plcs_[static_cast<std::size_t>(reach.wiring.plc)]->channel_names.at(
      static_cast<std::size_t>(reach.wiring.runner.channels.actuator));
  guard.experiment = reach.wiring.runner.experiment_name;
  guard.nominal_setpoint = nominal;
  guard.started_utime_us = ToUtime(WallNowS());
  try {
    // Blocking (write, fsync, rename, fsync of the directory: a few ms), once per experiment, on
    // the loop thread: the excitation write must wait for it, and the poller keeps polling.
    store_->SaveGuard(guard);
  } catch (const std::exception& e) {
    LogError(refused + " (" + e.what() + "): no excitation, restoring nominal " +
             std::to_string(nominal));
    return false;
  }
  reach.guard_on_disk = true;
  LogInfo("reach " + reach.name() + ": experiment guard persisted (" + guard.actuator +
          ", nominal " + std::to_string(nominal) + ")");
  return true;
}

void Daemon::OnRestoreConfirmed(Reach& reach) {
  const core::ExperimentPhase phase = reach.pipeline().experiment_state().phase;
  if (phase == core::ExperimentPhase::kSettling || phase == core::ExperimentPhase::kExciting)
    return;  // a new experiment's settling write, not an end: its guard stays
  if (reach.guard_on_disk && !reach.keep_guard) {
    try {
      store_->RemoveGuard(reach.name());
    } catch (const std::exception& e) {
      // The file stays and names a nominal the PLC has confirmed; the next experiment rewrites it.
      LogError(std::string("state: ") + e.what());
    }
    reach.guard_on_disk = false;
  }
  reach.runner.OnRestoreConfirmed();
}

void Daemon::SaveModel(const Reach& reach, const core::IdPipelineResult& result) {
  if (!store_) return;
  PersistedModel model;
  model.reach = reach.name();
  model.model_kind = "id";
  model.saved_utime_us = ToUtime(WallNowS());
  model.model = drivers::ToJson(result);
  if (const core::OnlineIdBank* bank = reach.pipeline().online_id()) {
    const core::IdSnapshot s = bank->Snapshot();
    model.online = {{"delay_s", s.delay_s},
                    {"area_m2", s.area_m2},
                    {"b", s.b},
                    {"area_std_m2", s.area_std_m2},
                    {"samples", bank->health().samples}};
  }
  try {
    store_->Save(model);
  } catch (const std::exception& e) {
    LogError(std::string("state: ") + e.what());
  }
}

void Daemon::StartCommands() {
  if (!plan_.commands_enabled) return;
  core::CommandAuthOptions options;
  options.enabled = true;
  options.max_clock_skew_s = plan_.command_max_clock_skew_s;
  {
    const core::SecretBytes key = ReadKeyFile(plan_.command_key_file);  // wiped at the brace
    authenticator_ = std::make_unique<core::CommandAuthenticator>(options, key.span());
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
  command_receiver_ = std::make_unique<drivers::CommandReceiver>(
      bus_, plan_.channel_prefix + "COMMAND", *authenticator_, [] { return ToUtime(WallNowS()); },
      [this](const drivers::AcceptedCommand& command) { OnCommand(command); });
  LogInfo("commands enabled on " + plan_.channel_prefix + "COMMAND");
}

void Daemon::OnCommand(const drivers::AcceptedCommand& command) {
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
  if (command.kind == core::CommandKind::kPublishConfig) {
    publisher_.PublishConfig(plan_.config_path, plan_.config_text, WallNowS());
    return;
  }
  for (auto& reach : reaches_) {
    if (reach->name() != command.reach) continue;
    LogInfo("command from " + command.sender + " for reach " + command.reach);
    switch (command.kind) {
      case core::CommandKind::kStartExperiment:
        if (!reach->pipeline().experiment_plan()) {
          LogWarning("reach " + command.reach + ": no experiment to start");
        } else if (!reach->runner.excitation_allowed()) {
          LogWarning("reach " + command.reach +
                     ": experiment refused: an interrupted experiment's nominal is not restored "
                     "(see the start-up log)");
        } else if (!stopping_) {
          Handle(*reach, reach->pipeline().StartExperiment(), reach->last_time_s);
        }
        break;
      case core::CommandKind::kAbortExperiment:
        Handle(*reach, reach->pipeline().StopExperiment(), reach->last_time_s);
        break;
      case core::CommandKind::kResetEstimator:
        reach->pipeline().ResetOnlineEstimator();
        // Marks the reset in the record (`canalid replay` resets its bank here too).
        if (const core::OnlineIdBank* bank = reach->pipeline().online_id()) {
          publisher_.PublishOnlineId(reach->name(), bank->Snapshot(), reach->last_time_s,
                                     "rls-bank-reset");
        }
        break;
      case core::CommandKind::kPublishConfig:
        break;
    }
    return;
  }
  LogWarning("command from " + command.sender + " names an unknown reach '" + command.reach + "'");
}

void Daemon::LogRejectedCommands(bool flush) {
  if (!command_receiver_) return;
  const double now = SteadyNowS();
  for (int v = 1; v < core::kNumCommandVerdicts; ++v) {
    const auto verdict = static_cast<core::CommandVerdict>(v);
    const auto index = static_cast<std::size_t>(v);
    const int64_t count = command_receiver_->count(verdict);
    const int64_t unlogged = count - verdicts_logged_[index];
    if (unlogged == 0) continue;
    // At most one line a second per verdict (the first at once), with the count: a flood of bad
    // messages must not flood the journal or block the loop on a slow log.
    if (!flush && now - verdict_logged_at_s_[index] < 1.0) continue;
    LogWarning(std::string("command rejected (") + core::CommandVerdictName(verdict) + ")" +
               (unlogged > 1 ? " x" + std::to_string(unlogged) : std::string()));
    verdicts_logged_[index] = count;
    verdict_logged_at_s_[index] = now;
  }
}

void Daemon::PublishHealth() {
  const double wall = WallNowS();
  const double uptime = SteadyNowS() - start_steady_s_;
  for (const auto& plc : plcs_) {
    const drivers::PollerCounters c = plc->poller->counters();
    HealthReport report;
    report.component = "plc." + plc->wiring.poller.plc_name;
    report.counters = {{"polls", c.polls},
                       {"block_reads_ok", c.block_reads_ok},
                       {"connect_failures", c.connect_failures},
                       {"reconnects", c.reconnects},
                       {"samples_dropped", c.samples_dropped},
                       {"overruns", c.overruns},
                       {"writes_ok", c.writes_ok},
                       {"writes_failed", c.writes_failed}};
    for (int k = 1; k < drivers::kPlcErrorKindCount; ++k) {
      report.counters.emplace_back(
          std::string("read_errors.") + ReadErrorCounterName(static_cast<drivers::PlcErrorKind>(k)),
          c.read_errors[static_cast<std::size_t>(k)]);
    }
    report.gauges = {{"last_round_trip_s", c.last_round_trip_s},
                     {"connected", c.connected ? 1.0 : 0.0},
                     {"current_backoff_s", c.current_backoff_s}};
    publisher_.PublishHealth(report, uptime, wall);
  }
  HealthReport bus;
  bus.component = "lcm";
  bus.counters = {{"handler_failures", bus_.handler_failures()},
                  {"publish_failures", publisher_.failures()},
                  {"losses", bus_losses_},
                  {"reconnects", bus_reconnects_}};
  publisher_.PublishHealth(bus, uptime, wall);
  if (command_receiver_) {
    HealthReport commands;
    commands.component = "commands";
    for (int v = 0; v < core::kNumCommandVerdicts; ++v) {
      const auto verdict = static_cast<core::CommandVerdict>(v);
      commands.counters.emplace_back(std::string("verdicts.") + core::CommandVerdictName(verdict),
                                     command_receiver_->count(verdict));
    }
    commands.counters.emplace_back("callback_failures", command_receiver_->callback_failures());
    publisher_.PublishHealth(commands, uptime, wall);
  }
  for (const auto& reach : reaches_) {
    HealthReport report;
    report.component = "reach." + reach->name();
    report.counters = {{"samples", reach->pipeline().samples()}};
    if (const core::OnlineIdBank* bank = reach->pipeline().online_id()) {
      const core::IdBankHealth& h = bank->health();
      report.counters.insert(report.counters.end(), {{"bad_flow_samples", h.bad_flow_samples},
                                                     {"bad_level_samples", h.bad_level_samples},
                                                     {"delay_switches", h.switches}});
    }
    publisher_.PublishHealth(report, uptime, wall);
    if (const auto& plan = reach->pipeline().experiment_plan()) {
      publisher_.PublishExperiment(
          reach->name(), reach->pipeline().experiment_state(), *plan,
          plcs_[static_cast<std::size_t>(reach->wiring.plc)]
              ->channel_names[static_cast<std::size_t>(reach->wiring.runner.channels.actuator)],
          wall);
    }
  }
}

void Daemon::BeginStop(DaemonExit exit) {
  if (stopping_) return;
  exit_ = exit;
  NotifyStopping();
  for (auto& reach : reaches_)
    Handle(*reach, reach->pipeline().StopExperiment(), reach->last_time_s);
  stopping_ = true;
  health_timer_.cancel();
  for (auto& plc : plcs_) plc->heartbeat_timer.cancel();
  stop_deadline_s_ = SteadyNowS() + stop_timeout_s;
  FinishStopWhenSafe();
}

void Daemon::FinishStopWhenSafe() {
  bool pending = false;
  for (const auto& reach : reaches_) pending = pending || reach->restore_pending;
  if (pending && SteadyNowS() < stop_deadline_s_) {
    // Write results arrive through Drain; re-check at least every 50 ms until the deadline.
    stop_timer_.expires_after(std::chrono::milliseconds(50));
    stop_timer_.async_wait([this](const boost::system::error_code& error) {
      if (!error) FinishStopWhenSafe();
    });
    return;
  }
  if (pending) LogError("stopping with a nominal setpoint not confirmed by the PLC");
  LogRejectedCommands(true);
  PublishHealth();
  signals_.cancel();
  if (bus_fd_) bus_fd_->cancel();
  bus_retry_timer_.cancel();
  stop_timer_.cancel();
  io_.stop();
}

std::string Daemon::Status() const {
  std::ostringstream s;
  for (const auto& reach : reaches_) {
    const core::ExperimentState& e = reach->pipeline().experiment_state();
    s << reach->name() << ": " << core::ExperimentPhaseName(e.phase);
    if (e.phase == core::ExperimentPhase::kExciting) {
      s << " " << e.samples_in_phase << "/" << reach->pipeline().experiment_plan()->excite_samples;
    }
    s << "; ";
  }
  return s.str();
}

}  // namespace canalid::daemon
