#include "daemon/canalid/replay_session.h"

#include <algorithm>
#include <utility>

#include "daemon/canalid/input_error.h"
#include "daemon/config/plan_from_config.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

bool LiveRunning(std::int8_t state) {
  return state == canalid::experiment_state_t::STATE_SETTLING ||
         state == canalid::experiment_state_t::STATE_EXCITING;
}

std::string At(const std::string& log, const drivers::LogEvent& event) {
  return log + ": byte " + std::to_string(event.offset);
}

}  // namespace

struct ReplaySession::Plc {
  std::string name;
  std::optional<std::int64_t> last_sequence;
  std::vector<int> reaches;
};

struct ReplaySession::Reach {
  config::ReachConfig config;
  std::optional<core::ReachController> runner;  // built at the first sample of its PLC in a run
  std::optional<ReplayModel> last_batch;
  std::map<std::string, ReplayModel> last_process_batch;  // idz and process models, by kind
  double last_time_s = 0.0;
  // The live run ended its excitation while this replay's experiment still runs: said once per
  // experiment of the replay's (the daemon publishes the state again with its health).
  bool live_end_reported = false;
};

ReplaySession::ReplaySession(ReplaySessionOptions options, ModelSink on_model,
                             WarningSink on_warning)
    : options_(std::move(options)),
      on_model_(std::move(on_model)),
      on_warning_(std::move(on_warning)),
      config_(options_.config) {}

ReplaySession::~ReplaySession() = default;

void ReplaySession::OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) {
  // Takes effect when the daemon that published it polls (see Restart); a configuration published
  // again on command, without a restart, changes nothing.
  config_.OnConfig(config, event, options_.log_path);
}

void ReplaySession::Restart() {
  plcs_.clear();
  reaches_.clear();
  const config::DaemonConfig& config = *config_.config();
  if (!options_.reach.empty() && config.FindReach(options_.reach) == nullptr) {
    std::string known;
    for (const auto& r : config.reaches) known += (known.empty() ? "" : ", ") + r.name;
    throw InputError("--reach " + options_.reach + ": not a reach of the configuration (" + known +
                     ")");
  }
  for (const config::PlcConfig& plc : config.plcs) {
    auto p = std::make_unique<Plc>();
    p->name = plc.name;
    plcs_.push_back(std::move(p));
  }
  for (const config::ReachConfig& reach : config.reaches) {
    if (!options_.reach.empty() && reach.name != options_.reach) continue;
    const std::string plc = config_.ReachPlc(reach);
    for (auto& p : plcs_) {
      if (p->name == plc) p->reaches.push_back(static_cast<int>(reaches_.size()));
    }
    auto r = std::make_unique<Reach>();
    r->config = reach;
    reaches_.push_back(std::move(r));
  }
  std::vector<std::string> names;
  for (const auto& r : reaches_) names.push_back(r->config.name);
  joints_ = core::JointExperiments(config::BuildJointExperiments(config, names));
  controllers_.assign(reaches_.size(), nullptr);  // each set when its runner is built
}

ReplaySession::Plc* ReplaySession::FindPlc(const std::string& name) {
  for (auto& p : plcs_) {
    if (p->name == name) return p.get();
  }
  return nullptr;
}

void ReplaySession::OnSample(const std::string& plc_name, const canalid::sample_t& sample,
                             const drivers::LogEvent& event) {
  if (!config_.config()) return;  // FinalModels() says why nothing was replayed
  if (!first_utime_) first_utime_ = sample.utime;
  const double t = static_cast<double>(sample.utime - *first_utime_) * 1e-6;
  if (plcs_.empty() && reaches_.empty()) Restart();
  Plc* plc = FindPlc(plc_name);
  if (plc == nullptr) return;  // a PLC of another configuration
  if (plc->last_sequence && sample.sequence <= *plc->last_sequence) {
    on_warning_(At(options_.log_path, event) + ": PLC " + plc_name + " polls from sequence " +
                std::to_string(sample.sequence) +
                " again: the daemon restarted; the reaches start again");
    Restart();
    plc = FindPlc(plc_name);
  }
  plc->last_sequence = sample.sequence;
  if ((options_.from_s && t < *options_.from_s) || (options_.to_s && t > *options_.to_s)) return;
  ++samples_used_;
  const bool status_ok = sample.status == canalid::sample_t::STATUS_OK;
  const bool link_ok = sample.status != canalid::sample_t::STATUS_DISCONNECTED;
  for (const int index : plc->reaches) {
    Reach& reach = *reaches_[static_cast<std::size_t>(index)];
    reach.last_time_s = t;
    if (!reach.runner) {
      reach.runner.emplace(
          config_.RunnerOptions(reach.config, sample, At(options_.log_path, event)));
      controllers_[static_cast<std::size_t>(index)] = &*reach.runner;
      if (!reach.runner->initial_plan_error().empty()) {
        on_warning_("reach " + reach.config.name +
                    ": no experiment: " + reach.runner->initial_plan_error());
      }
      // The daemon that polls here found an interrupted experiment at its start.
      if (const auto restart = pending_restarts_.find(reach.config.name);
          restart != pending_restarts_.end()) {
        const auto decision = core::RestartDecisionFromMessage(
            restart->second.first, restart->second.second, reach.config.nominal_setpoint);
        const std::string error = reach.runner->ApplyRestart(*decision);
        if (!error.empty()) on_warning_("reach " + reach.config.name + ": no experiment: " + error);
        pending_restarts_.erase(restart);
      }
    }
    const core::ReachReadings readings = core::ReadReach(
        reach.runner->options().channels, sample.values,
        [&](std::size_t i) { return sample.quality[i] == canalid::sample_t::QUALITY_VALID; },
        link_ok, status_ok, t);
    const core::ReachPollOutcome outcome = reach.runner->OnPoll(readings);
    if (!outcome.plan_error.empty())
      on_warning_("reach " + reach.config.name + ": no experiment: " + outcome.plan_error);
    Step(reach, outcome.actions, t);
  }
  // Once every reach has taken the poll, as the daemon does.
  for (const int index : plc->reaches) {
    Reach& reach = *reaches_[static_cast<std::size_t>(index)];
    const bool allowed = reach.runner->on_start_done() ||
                         joints_.OnStartAllowed(controllers_, static_cast<std::size_t>(index));
    if (const auto start = reach.runner->StartIfDue(status_ok, allowed)) Step(reach, *start, t);
  }
  if (options_.snapshot_every > 0 && samples_used_ % options_.snapshot_every == 0) {
    for (const auto& reach : reaches_) {
      OnlineModels(*reach, t, true, [&](const ReplayModel& model) { on_model_(model); });
    }
  }
}

void ReplaySession::Joint(const Reach& reach, const core::ReachActions& actions) {
  if (!actions.experiment_phase_changed) return;
  // The joint experiments' starts and stops, at the same points as the daemon's.
  std::size_t index = 0;
  for (std::size_t i = 0; i < reaches_.size(); ++i) {
    if (reaches_[i].get() == &reach) index = i;
  }
  for (const core::JointOrder& order : joints_.AfterPhaseChange(controllers_, index)) {
    Reach& other = *reaches_[order.reach];
    Step(other, order.actions, other.last_time_s);
  }
}

void ReplaySession::Step(Reach& reach, const core::ReachActions& actions, double log_time_s) {
  Joint(reach, actions);
  if (!core::IsRunning(reach.runner->pipeline().experiment_state().phase)) {
    reach.live_end_reported = false;
  }
  if (!actions.experiment_record_complete) return;
  core::ReachActions after;
  const core::ReachSampleProcessor& pipeline = reach.runner->pipeline();
  const std::optional<core::IntegratorDelayIdentification> result =
      reach.runner->IdentifyRecord(&after);
  Joint(reach, after);
  // The other batch kinds (idz, the process models), as the daemon publishes them.
  auto other_batch = [&](std::string kind, nlohmann::json json) {
    json["reach"] = reach.config.name;
    ReplayModel model;
    model.reach = reach.config.name;
    model.log_time_s = log_time_s;
    model.batch = true;
    model.kind = std::move(kind);
    model.estimator = "batch";
    model.json = std::move(json);
    reach.last_process_batch[model.kind] = model;
    on_model_(model);
  };
  if (pipeline.idz_result()) other_batch("idz", drivers::ToJson(*pipeline.idz_result()));
  for (const core::ProcessBatchResult& process : pipeline.process_batch_results()) {
    std::optional<nlohmann::json> json =
        drivers::ProcessBatchJson(process, pipeline.options().sample_time_s);
    if (json) other_batch(std::string(core::ProcessBatchKindName(process.kind)), std::move(*json));
  }
  if (!result) {
    if (pipeline.options().batch_id) {
      on_warning_("reach " + reach.config.name + ": the experiment record could not be identified");
    }
    return;
  }
  ReplayModel model;
  model.reach = reach.config.name;
  model.log_time_s = log_time_s;
  model.batch = true;
  model.estimator = "batch";
  model.json = drivers::ToJson(*result);
  model.json["reach"] = reach.config.name;
  reach.last_batch = model;
  on_model_(model);
}

void ReplaySession::OnExperiment(const canalid::experiment_state_t& live,
                                 const drivers::LogEvent& event) {
  // Published by a daemon at start, before its first poll: it belongs to the reach's next runner
  // (whose configuration may be the one this daemon published just before).
  if (core::RestartDecisionFromMessage(live.reason, live.setpoint, std::nullopt)) {
    pending_restarts_[live.reach] = {live.reason, live.setpoint};
    return;
  }
  for (std::size_t index = 0; index < reaches_.size(); ++index) {
    const std::unique_ptr<Reach>& reach = reaches_[index];
    if (reach->config.name != live.reach || !reach->runner) continue;
    core::ReachController& runner = *reach->runner;
    // A joint end or stop the replay's own joint rules should have made already.
    auto joint_diverges = [&] {
      if (!joints_.HasOtherMember(index, live.experiment)) return;
      on_warning_(At(options_.log_path, event) + ": reach " + live.reach +
                  ": the live experiment " +
                  (live.state == canalid::experiment_state_t::STATE_DONE ? "ended" : "stopped") +
                  " with its joint experiment where the replay's did not: the replay diverges "
                  "from the live run");
    };
    const core::ExperimentPhase ours = runner.pipeline().experiment_state().phase;
    const double t = first_utime_ ? static_cast<double>(live.utime - *first_utime_) * 1e-6 : 0.0;
    if (LiveRunning(live.state) && !core::IsRunning(ours)) {
      // Started by an operator command between two polls.
      Step(*reach, runner.Start(live.experiment), t);
      if (!core::IsRunning(runner.pipeline().experiment_state().phase)) {
        on_warning_(At(options_.log_path, event) + ": reach " + live.reach + ": the live run " +
                    "started experiment '" + live.experiment + "', which the replay cannot (" +
                    runner.StartRefusal(live.experiment) + ")");
      }
    } else if (live.state == canalid::experiment_state_t::STATE_DONE &&
               live.reason == core::kEndedWithJoint && core::IsRunning(ours)) {
      // Ended with a joint experiment whose leader this replay does not run (--reach); when it
      // runs the leader too, its own joint rules should have ended it: a divergence.
      joint_diverges();
      Step(*reach, runner.EndJoint(), t);
    } else if ((live.state == canalid::experiment_state_t::STATE_RECOVERING ||
                live.state == canalid::experiment_state_t::STATE_DONE) &&
               core::IsRunning(ours)) {
      // The live excitation ended on its own.  The daemon publishes that after the sample of the
      // same poll, which the replay has already run: its experiment runs on, so its samples or
      // rules differ from the live run's.
      if (!reach->live_end_reported) {
        on_warning_(At(options_.log_path, event) + ": reach " + live.reach +
                    ": the live experiment ended its excitation where the replay's still runs: "
                    "the replay diverges from the live run");
        reach->live_end_reported = true;
      }
    } else if (live.state == canalid::experiment_state_t::STATE_ABORTED && core::IsRunning(ours)) {
      // Ended by something the samples do not carry.
      if (live.reason == core::AbortReasonName(core::AbortReason::kLinkLost)) {
        Step(*reach, runner.OnLinkLost(), t);
      } else if (live.reason == core::AbortReasonName(core::AbortReason::kWriteFailed)) {
        Step(*reach, runner.OnWriteResult({false, 0.0}).actions, t);
      } else if (live.reason == core::AbortReasonName(core::AbortReason::kGuardNotPersisted)) {
        Step(*reach, runner.OnGuardNotPersisted(), t);
      } else if (live.reason == core::AbortReasonName(core::AbortReason::kJointStop)) {
        // Stopped with a joint experiment whose other reach this replay does not run (--reach);
        // else a divergence, as above.
        joint_diverges();
        Step(*reach, runner.StopJoint(), t);
      } else {
        if (live.reason != core::AbortReasonName(core::AbortReason::kOperatorStop)) {
          on_warning_(At(options_.log_path, event) + ": reach " + live.reach +
                      ": the live experiment aborted (" + live.reason +
                      ") where the replay's did not: the replay diverges from the live run");
        }
        Step(*reach, runner.Stop(), t);
      }
    }
  }
}

void ReplaySession::OnModel(const canalid::model_snapshot_t& model,
                            const drivers::LogEvent& /*event*/) {
  if (model.estimator == "rls-bank-reset") {
    // An operator reset the online estimator between two polls.
    for (auto& reach : reaches_) {
      if (reach->config.name == model.reach && reach->runner) reach->runner->ResetOnlineEstimator();
    }
    return;
  }
  live_models_[model.reach][LiveKey(model.model_kind, model.estimator)] = model;
}

ReplayModel ReplaySession::OnlineIdModel(const Reach& reach, double log_time_s) const {
  const core::OnlineIntegratorDelayBank& bank = *reach.runner->pipeline().online_id();
  const core::IntegratorDelaySnapshot s = bank.Snapshot();
  ReplayModel model;
  model.reach = reach.config.name;
  model.log_time_s = log_time_s;
  model.estimator = "rls-bank";
  model.json =
      drivers::OnlineIntegratorDelayJson(s, reach.runner->options().pipeline.sample_time_s);
  model.json["samples"] = bank.health().samples;
  model.json["reach"] = reach.config.name;
  return model;
}

void ReplaySession::OnlineModels(const Reach& reach, double log_time_s, bool with_id,
                                 const std::function<void(ReplayModel)>& sink) const {
  if (!reach.runner) return;
  core::OnlineModelSnapshot snapshot;
  for (const auto& online : reach.runner->pipeline().online_models()) {
    online->FillSnapshot(snapshot);
    if (!snapshot.valid) continue;
    if (online->kind() == core::OnlineModelKind::kIntegratorDelay) {
      if (with_id) sink(OnlineIdModel(reach, log_time_s));
      continue;
    }
    ReplayModel model;
    model.reach = reach.config.name;
    model.log_time_s = log_time_s;
    model.kind = core::OnlineModelKindName(snapshot.kind);
    model.estimator = snapshot.estimator;
    model.json = drivers::OnlineModelJson(snapshot, reach.runner->options().pipeline.sample_time_s);
    model.json["reach"] = reach.config.name;
    sink(std::move(model));
  }
}

std::vector<std::string> ReplaySession::ReachesWithoutModels() const {
  std::vector<std::string> names;
  for (const auto& reach : reaches_) {
    if (reach->config.online_models.empty() && reach->config.batch_models.empty())
      names.push_back(reach->config.name);
  }
  return names;
}

std::vector<ReplayModel> ReplaySession::FinalModels() const {
  std::vector<ReplayModel> models;
  for (const auto& reach : reaches_) {
    OnlineModels(*reach, reach->last_time_s, false,
                 [&](ReplayModel model) { models.push_back(std::move(model)); });
    for (const auto& [kind, model] : reach->last_process_batch) models.push_back(model);
    if (reach->last_batch) {
      models.push_back(*reach->last_batch);
    } else if (reach->runner && reach->runner->pipeline().online_id() != nullptr &&
               reach->runner->pipeline().online_id()->Snapshot().valid) {
      models.push_back(OnlineIdModel(*reach, reach->last_time_s));
    }
  }
  return models;
}

}  // namespace canalid::cli
