#include "daemon/canalidd/daemon.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "core/reach/stop_rule.h"
#include "daemon/canalidd/clock.h"
#include "daemon/canalidd/health_report.h"
#include "daemon/canalidd/log.h"
#include "daemon/canalidd/model_persistence.h"
#include "daemon/canalidd/restore_safety.h"
#include "daemon/canalidd/startup_check.h"
#include "daemon/canalidd/systemd_notify.h"
#include "drivers/json/model_json.h"
#include "drivers/modbus/modbus_port.h"
#include "drivers/modbus/results_server.h"

namespace canalid::daemon {
namespace {

std::string NoProcessModelMessage(const std::string& reach, const std::string& kind,
                                  const std::string& problem) {
  return "reach " + reach + ": no " + kind + " model: " + problem;
}

}  // namespace

Daemon::Daemon(DaemonPlan plan, drivers::Bus& bus, PortFactory make_port, ReloadFunction reload)
    : plan_(std::move(plan)),
      bus_(bus),
      make_port_(std::move(make_port)),
      reload_(std::move(reload)),
      signals_(
          io_, [this] { BeginStop(DaemonExit::kStopped); }, [this] { return Reload(); }),
      bus_watch_(
          io_, bus_, [this] { commands_.LogRejected(false); }, [this] { return stopping_; },
          [](bool lost, const std::string& text) { lost ? LogError(text) : LogInfo(text); }),
      health_timer_(io_),
      stop_timer_(io_),
      publisher_(bus_, plan_.channel_prefix),
      commands_(plan_, bus_, [this](const drivers::AcceptedCommand& c) { OnCommand(c); }) {
  for (std::size_t i = 0; i < plan_.plcs.size(); ++i) {
    const PlcWiring& wiring = plan_.plcs[i];
    auto plc = std::make_unique<PlcRuntime>(wiring);
    for (const auto& channel : wiring.poller.channels) plc->channel_names.push_back(channel.name);
    PlcRuntime* raw = plc.get();
    const int index = static_cast<int>(i);
    // The poller thread only posts a drain; the flag keeps a burst of notifications to one.
    plc->poller =
        std::make_unique<drivers::PlcPoller>(wiring.poller, make_port_(wiring), [this, raw, index] {
          if (!raw->drain_pending.exchange(true))
            boost::asio::post(io_, [this, index] { Drain(index); });
        });
    plc->heartbeat =
        std::make_unique<Heartbeat>(io_, *plc->poller, wiring.heartbeat_channel,
                                    wiring.heartbeat_period_s, [this] { return stopping_; });
    plcs_.push_back(std::move(plc));
  }
  for (std::size_t r = 0; r < plan_.reaches.size(); ++r) {
    auto reach = std::make_unique<ReachRuntime>(plan_.reaches[r]);
    reach->index = static_cast<int>(r);
    if (!reach->runner.initial_plan_error().empty())
      LogError("reach " + reach->name() + ": no experiment: " + reach->runner.initial_plan_error());
    plcs_.at(static_cast<std::size_t>(reach->wiring.plc))->reaches.push_back(static_cast<int>(r));
    controllers_.push_back(&reach->runner);
    reaches_.push_back(std::move(reach));
  }
  joints_ = core::JointExperiments(plan_.joints);
}

Daemon::~Daemon() {
  publisher_.SetModelObserver(nullptr);  // results_ goes first
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
    if (plan_.results_enabled) {
      results_ = std::make_unique<ResultsFeed>(plan_);
      publisher_.SetModelObserver(
          [this](const canalid::model_snapshot_t& model) { results_->OnModel(model); });
      LogInfo("results map: serving " + std::to_string(reaches_.size()) + " reach(es) on " +
              plan_.results_host + ":" + std::to_string(results_->port()) +
              " (Modbus TCP, read-only)");
    }
    LoadState();
    for (auto& reach : reaches_) {
      const int actuator = reach->wiring.runner.channels.actuator;
      if (actuator < 0) continue;
      ResumeInterruptedExperiment(*reach,
                                  plcs_[static_cast<std::size_t>(reach->wiring.plc)]
                                      ->wiring.poller.channels[static_cast<std::size_t>(actuator)],
                                  store(), publisher_);
    }
    commands_.Start(store());
    signals_.Start();
    bus_watch_.Start();
    StartHealthTimer();
    for (auto& plc : plcs_) plc->poller->Start();
    for (auto& plc : plcs_) plc->heartbeat->Start();
  } catch (const std::exception& e) {
    throw StartupError(e.what());  // canalidd exits 78: nothing has run yet
  }
  LogInfo("running: " + std::to_string(plcs_.size()) + " PLC(s), " +
          std::to_string(reaches_.size()) + " reach(es), LCM prefix " + plan_.channel_prefix);
  io_.run();
  for (auto& plc : plcs_) plc->poller->Stop();
  // Every model queued before the stop is on disk before Run returns (and a reload reads it).
  if (model_saver_) model_saver_->Stop();
  LogInfo(exit_ == DaemonExit::kReload ? "reloading the configuration" : "stopped");
  return exit_;
}

bool Daemon::Reload() {
  std::optional<DaemonPlan> plan;
  try {
    plan = reload_ ? reload_() : std::nullopt;
  } catch (const std::exception& e) {
    LogError(std::string("reload failed: ") + e.what());
  }
  if (!plan) {
    LogWarning("the new configuration is not valid; carrying on with the running one");
    return false;
  }
  // A results map moved to another address: that address must be free before this daemon stops
  // (the new one could not serve it, and would exit).  The same address is handed over.
  if (plan->results_enabled &&
      (!plan_.results_enabled || plan->results_host != plan_.results_host ||
       plan->results_port != plan_.results_port)) {
    const std::string problem =
        drivers::ResultsListenProblem(plan->results_host, std::to_string(plan->results_port));
    if (!problem.empty()) {
      LogWarning("the new configuration's results map cannot listen on " + plan->results_host +
                 ":" + std::to_string(plan->results_port) + " (" + problem +
                 "); carrying on with the running one");
      return false;
    }
  }
  reloaded_plan_ = std::move(plan);
  NotifyReloading();
  BeginStop(DaemonExit::kReload);
  return true;
}

void Daemon::StartHealthTimer() {
  health_timer_.expires_after(Seconds(plan_.health_period_s));
  health_timer_.async_wait([this](const boost::system::error_code& error) {
    if (error || stopping_) return;
    commands_.LogRejected(true);
    PublishHealth();
    // The watchdog is fed from the sample loop; with every link down there are no samples, so the
    // health timer keeps systemd informed that the loop itself is alive.
    NotifyWatchdog();
    StartHealthTimer();
  });
}

void Daemon::Drain(int index) {
  PlcRuntime& plc = *plcs_[static_cast<std::size_t>(index)];
  plc.drain_pending = false;
  plc.poller->DrainSamples([&](const drivers::PollSample& s) { OnPoll(index, s); });
  plc.poller->DrainWriteResults([&](const drivers::WriteResult& r) { OnWriteResult(index, r); });
  // While the poller reconnects no samples arrive, so a running experiment would never hear of
  // the lost link from a sample (after timeouts the link drops without a disconnected poll).
  if (!plc.poller->counters().connected) {
    for (const int r : plc.reaches) {
      ReachRuntime& reach = *reaches_[static_cast<std::size_t>(r)];
      Handle(reach, reach.runner.OnLinkLost(), reach.last_time_s);
    }
  }
}

void Daemon::OnPoll(int index, const drivers::PollSample& s) {
  PlcRuntime& plc = *plcs_[static_cast<std::size_t>(index)];
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
    ReachRuntime& reach = *reaches_[static_cast<std::size_t>(r)];
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
    if (outcome.actions.online_updated) PublishOnlineModels(reach, outcome.actions, s.time_s);
    if (results_) results_->OnReachPoll(r, s, readings);
  }
  // Once every reach has taken the poll (a joint experiment's partners know their nominals).
  for (const int r : plc.reaches) {
    ReachRuntime& reach = *reaches_[static_cast<std::size_t>(r)];
    // Asked of the joints only while the on_start experiment waits (no work per poll after).
    const bool allowed =
        !stopping_ && (reach.runner.on_start_done() ||
                       joints_.OnStartAllowed(controllers_, static_cast<std::size_t>(r)));
    if (const auto start = reach.runner.StartIfDue(s.status.ok(), allowed)) {
      LogInfo("reach " + reach.name() + ": starting the experiment " +
              reach.runner.experiment_name());
      Handle(reach, *start, s.time_s);
    }
  }
}

void Daemon::PublishOnlineModels(ReachRuntime& reach, const core::ReachActions& actions,
                                 double time_s) {
  const auto& models = reach.pipeline().online_models();
  const std::int64_t sample = reach.pipeline().samples();
  for (std::size_t i = 0; i < models.size(); ++i) {
    if ((actions.online_models_updated & (std::uint32_t{1} << i)) == 0) continue;
    std::int64_t& last = reach.published_at[i];
    if (last >= 0 && sample - last < reach.wiring.model_publish_every) continue;
    models[i]->FillSnapshot(snapshot_);
    if (!snapshot_.valid) continue;
    publisher_.PublishOnlineModel(reach.name(), snapshot_, time_s);
    last = sample;
  }
}

void Daemon::OnWriteResult(int index, const drivers::WriteResult& result) {
  PlcRuntime& plc = *plcs_[static_cast<std::size_t>(index)];
  if (result.channel == plc.wiring.heartbeat_channel) {
    if (result.outcome != drivers::WriteOutcome::kWritten) LogDebug("heartbeat write failed");
    return;
  }
  for (const int r : plc.reaches) {
    ReachRuntime& reach = *reaches_[static_cast<std::size_t>(r)];
    if (reach.wiring.runner.channels.actuator != result.channel) continue;
    const bool written = result.outcome == drivers::WriteOutcome::kWritten;
    const core::ReachWriteOutcome outcome =
        reach.runner.OnWriteResult({written, result.written, result.id});
    if (outcome.restore_confirmed) {
      LogInfo("reach " + reach.name() + ": nominal setpoint " + std::to_string(result.written) +
              " restored");
    }
    if (outcome.remove_guard) RemoveGuard(reach, store());
    if (!written) {
      LogWarning("reach " + reach.name() + ": setpoint write failed (" +
                 drivers::PlcErrorKindName(result.plc.kind) + ")");
      Handle(reach, outcome.actions, reach.last_time_s);
    }
  }
  if (stopping_) FinishStopWhenSafe();
}

void Daemon::RequestSetpoint(ReachRuntime& reach, double value) {
  const drivers::WriteTicket ticket =
      plcs_[static_cast<std::size_t>(reach.wiring.plc)]->poller->RequestWrite(
          reach.wiring.runner.channels.actuator, value);
  if (ticket.status != drivers::WriteQueueStatus::kQueued) {
    LogWarning("reach " + reach.name() + ": setpoint write not queued");
    return;
  }
  reach.runner.OnWriteQueued(ticket.id);
}

void Daemon::Handle(ReachRuntime& reach, const core::ReachActions& actions, double time_s) {
  const std::string& name = reach.name();
  const int actuator = reach.wiring.runner.channels.actuator;
  if (actions.write_setpoint && actuator >= 0) {
    if (reach.runner.needs_guard(actions) &&
        !PersistGuard(reach, ActuatorName(plcs_, reach), store())) {
      // No excitation write without a durable guard: abort instead, which restores the nominal.
      Handle(reach, reach.runner.OnGuardNotPersisted(), time_s);
      return;
    }
    RequestSetpoint(reach, *actions.write_setpoint);
  }
  const auto& plan = reach.pipeline().experiment_plan();
  if (actions.experiment_phase_changed && plan) {
    const core::ExperimentState& state = reach.pipeline().experiment_state();
    publisher_.PublishExperiment(name, reach.runner.experiment_name(), state, *plan,
                                 ActuatorName(plcs_, reach), time_s);
    std::string message =
        "reach " + name + ": experiment " + core::ExperimentPhaseName(state.phase);
    // Why it aborted, or that it ended with its joint experiment.
    if (state.phase == core::ExperimentPhase::kAborted || state.ended_with_joint)
      message += " (" + core::PhaseReasonText(*plan, state) + ")";
    (state.phase == core::ExperimentPhase::kAborted ? LogWarning(message) : LogInfo(message));
    NotifyStatus(Status());
  }
  if (actions.experiment_phase_changed) {
    for (const core::JointOrder& order :
         joints_.AfterPhaseChange(controllers_, static_cast<std::size_t>(reach.index))) {
      ReachRuntime& other = *reaches_[order.reach];
      const std::string text = "reach " + other.name() + ": joint experiment: " + order.why;
      const bool stopped =
          other.pipeline().experiment_state().phase == core::ExperimentPhase::kAborted;
      (stopped ? LogWarning(text) : LogInfo(text));
      Handle(other, order.actions, other.last_time_s);
    }
  }
  if (actions.experiment_record_complete) {
    core::ReachActions after;
    const std::optional<core::IntegratorDelayIdentification> result =
        reach.runner.IdentifyRecord(&after);
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
    } else if (reach.pipeline().options().batch_id) {
      LogWarning("reach " + name + ": the experiment record could not be identified");
    }
    ReportIdzModel(reach, time_s);
    ReportProcessModels(reach, time_s);
    Handle(reach, after, time_s);
  }
  // Every path that moves the experiment (a poll, a lost link, a failed write, a command) ends
  // here: the results map shows its state at once, also while no poll comes.
  if (results_) results_->OnReachState(reach.index, reach.runner);
}

void Daemon::ReportIdzModel(const ReachRuntime& reach, double time_s) {
  const std::string& name = reach.name();
  const std::optional<core::IdzIdentification>& result = reach.pipeline().idz_result();
  const std::string& problem = reach.pipeline().idz_problem();
  if (!reach.pipeline().options().batch_idz) return;
  if (!result) {
    LogWarning("reach " + name + ": no idz model: " + problem);
    return;
  }
  nlohmann::json json = drivers::ToJson(*result);
  json["reach"] = name;
  const bool finite = std::isfinite(result->fit.area_m2) && std::isfinite(result->fit.p21_s_per_m2);
  PublishBatchModel(reach, "idz", json, problem, time_s, finite ? 0 : core::kFlagNan);
}

void Daemon::PublishBatchModel(const ReachRuntime& reach, const std::string& kind,
                               const nlohmann::json& json, const std::string& problem,
                               double time_s, std::int32_t flags) {
  const std::string& name = reach.name();
  publisher_.PublishModelJson(name, json, time_s, "batch", reach.pipeline().recorded_samples(),
                              flags | (problem.empty() ? 0 : core::kFlagOutOfBounds));
  if (!problem.empty()) {
    LogWarning("reach " + name + ": identified a " + kind + " model outside the bounds (" +
               problem + "); not persisted: " + json.dump());
    return;
  }
  LogInfo("reach " + name + ": identified " + kind + " " + json.dump());
  if (model_saver_) {
    PersistedModel model;
    model.reach = name;
    model.model_kind = kind;
    model.saved_utime_us = ToUtime(WallNowS());
    model.model = json;
    model_saver_->Submit(std::move(model));
  }
}

void Daemon::ReportProcessModels(const ReachRuntime& reach, double time_s) {
  const std::string& name = reach.name();
  for (const core::ProcessBatchResult& process : reach.pipeline().process_batch_results()) {
    const std::string kind(core::ProcessBatchKindName(process.kind));
    std::optional<nlohmann::json> json =
        drivers::ProcessBatchJson(process, reach.pipeline().options().sample_time_s);
    if (!json) {
      LogWarning(NoProcessModelMessage(name, kind, process.problem));
      continue;
    }
    (*json)["reach"] = name;
    PublishBatchModel(reach, kind, *json, process.ok() ? std::string() : process.problem, time_s);
  }
}

void Daemon::LoadState() {
  if (plan_.state_directory.empty()) return;
  store_.emplace(plan_.state_directory);
  ResumePersistedModels(*store_, reaches_, publisher_);
  // Its own store on the same directory: it writes only model files, which nothing on the loop
  // thread writes (guards and command counters are other files, each with its own temp file).
  // One slot per reach: a reach's newer model replaces its waiting one, so Submit never waits.
  model_saver_ = std::make_unique<PersistenceWorker>(
      [store = *store_](const PersistedModel& model) mutable { store.Save(model); },
      [](const std::string& what) { LogError("state: " + what); },
      std::max<std::size_t>(BatchModelCount(reaches_), 1));
}

void Daemon::SaveModel(const ReachRuntime& reach,
                       const core::IntegratorDelayIdentification& result) {
  if (!model_saver_) return;
  model_saver_->Submit(MakePersistedModel(reach, result, WallNowS()));
}

void Daemon::OnCommand(const drivers::AcceptedCommand& command) {
  if (command.kind == drivers::CommandKind::kPublishConfig) {
    publisher_.PublishConfig(plan_.config_path, plan_.config_text, WallNowS());
    return;
  }
  for (auto& reach : reaches_) {
    if (reach->name() != command.reach) continue;
    LogInfo("command from " + command.sender + " for reach " + command.reach);
    switch (command.kind) {
      case drivers::CommandKind::kStartExperiment:
        if (const std::string refusal = joints_.StartRefusal(
                controllers_, static_cast<std::size_t>(reach->index), command.argument);
            !refusal.empty()) {
          LogWarning("reach " + command.reach + ": start refused: " + refusal);
        } else if (!stopping_) {
          const core::ReachActions start = reach->runner.Start(command.argument);
          LogInfo("reach " + command.reach + ": starting the experiment " +
                  reach->runner.experiment_name());
          Handle(*reach, start, reach->last_time_s);
        }
        break;
      case drivers::CommandKind::kAbortExperiment:
        Handle(*reach, reach->runner.Stop(), reach->last_time_s);
        break;
      case drivers::CommandKind::kResetEstimator:
        reach->runner.ResetOnlineEstimator();
        // Marks the reset in the record (`canalid replay` resets its bank here too).
        if (!reach->pipeline().online_models().empty()) {
          reach->pipeline().online_models().front()->FillSnapshot(snapshot_);
          publisher_.PublishOnlineModel(reach->name(), snapshot_, reach->last_time_s,
                                        "rls-bank-reset");
        }
        break;
      case drivers::CommandKind::kPublishConfig:
        break;
    }
    return;
  }
  LogWarning("command from " + command.sender + " names an unknown reach '" + command.reach + "'");
}

void Daemon::PublishHealth() {
  const double wall = WallNowS();
  const double uptime = SteadyNowS() - start_steady_s_;
  for (const auto& plc : plcs_) {
    publisher_.PublishHealth(PlcHealth(plc->wiring.poller.plc_name, plc->poller->counters()),
                             uptime, wall);
  }
  publisher_.PublishHealth(BusHealth(bus_.handler_failures(), publisher_.failures(),
                                     bus_watch_.losses(), bus_watch_.reconnects()),
                           uptime, wall);
  if (const drivers::CommandReceiver* receiver = commands_.receiver())
    publisher_.PublishHealth(CommandHealth(*receiver), uptime, wall);
  if (results_) publisher_.PublishHealth(results_->Health(), uptime, wall);
  for (const auto& reach : reaches_) {
    publisher_.PublishHealth(ReachHealth(reach->name(), reach->pipeline()), uptime, wall);
    if (const auto& plan = reach->pipeline().experiment_plan()) {
      publisher_.PublishExperiment(reach->name(), reach->runner.experiment_name(),
                                   reach->pipeline().experiment_state(), *plan,
                                   ActuatorName(plcs_, *reach), wall);
    }
  }
}

void Daemon::BeginStop(DaemonExit exit) {
  if (stopping_) return;
  exit_ = exit;
  NotifyStopping();
  for (auto& reach : reaches_) Handle(*reach, reach->runner.Stop(), reach->last_time_s);
  stopping_ = true;
  health_timer_.cancel();
  for (auto& plc : plcs_) plc->heartbeat->Cancel();
  stop_deadline_s_ = SteadyNowS() + stop_timeout_s;
  FinishStopWhenSafe();
}

void Daemon::FinishStopWhenSafe() {
  bool pending = false;
  for (const auto& reach : reaches_) pending = pending || reach->runner.restore_pending();
  const core::StopProgress progress = core::DecideStop(pending, SteadyNowS(), stop_deadline_s_);
  if (progress == core::StopProgress::kWait) {
    // Write results arrive through Drain; re-check at least every 50 ms until the deadline.
    stop_timer_.expires_after(std::chrono::milliseconds(50));
    stop_timer_.async_wait([this](const boost::system::error_code& error) {
      if (!error) FinishStopWhenSafe();
    });
    return;
  }
  if (progress == core::StopProgress::kDeadlinePassed)
    LogError("stopping with a nominal setpoint not confirmed by the PLC");
  commands_.LogRejected(true);
  PublishHealth();
  signals_.Cancel();
  bus_watch_.Cancel();
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
