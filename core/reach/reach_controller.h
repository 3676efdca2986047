#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/experiment/experiment_guard.h"
#include "core/reach/reach_sample_processor.h"

namespace canalid::core {

/// Where a reach's values sit in its PLC's poll (indices into the PLC's channel list; -1: none).
struct ReachChannels {
  int q_in = -1;
  int q_out = -1;
  int level = -1;
  int actuator = -1;
  /// The actuator's measured position: the process models' input when given (else the actuator).
  int actuator_position = -1;
  int scheduling = -1;  ///< the lpv model's scheduling variable
};

/// One experiment a reach may run.
struct ReachExperiment {
  std::string name;  ///< unique among the reach's experiments; operators' commands name it
  /// The experiment's plan around a nominal setpoint.
  /// @throws std::invalid_argument when the nominal leaves no room for it inside the limits.
  std::function<ExperimentPlan(double nominal_setpoint)> plan_for_nominal;
  bool start_on_start = false;  ///< started by itself at the first complete poll (at most one)
};

/// Everything a reach runs, derived from the configuration (daemon/config/plan_from_config.h builds
/// it).
struct ReachControllerOptions {
  std::string name;
  ReachChannels channels;
  ReachSampleProcessorOptions pipeline;  ///< no experiment: they come from `experiments`
  /// The actuator's nominal setpoint; none: its first valid reading.
  std::optional<double> nominal_setpoint;
  /// The experiments the reach may run, in the configuration's order (none: never excited).
  std::vector<ReachExperiment> experiments;
};

/// One poll of a reach's PLC as the reach reads it: the channel values (engineering units) with
/// their validity, and the poll's status.
struct ReachReadings {
  double q_in_m3s = 0.0, q_out_m3s = 0.0, level_m = 0.0, actuator = 0.0;
  double actuator_position = 0.0, scheduling = 0.0;
  bool q_in_valid = false, q_out_valid = false, level_valid = false, actuator_valid = false;
  bool actuator_position_valid = false, scheduling_valid = false;
  bool link_ok = true;    ///< the PLC answered (a disconnected poll is not)
  bool status_ok = true;  ///< every block of the poll was read
  double time_s = std::numeric_limits<double>::quiet_NaN();  ///< when the poll was taken (s)
};

/// The reach's readings from a poll's values and per-channel validity (`valid(i)` for channel i).
template <class Values, class Valid>
ReachReadings ReadReach(const ReachChannels& c, const Values& values, Valid valid, bool link_ok,
                        bool status_ok, double time_s) {
  ReachReadings r;
  auto read = [&](int channel, double* value, bool* ok) {
    *ok = channel >= 0 && valid(static_cast<std::size_t>(channel));
    *value = *ok ? values[static_cast<std::size_t>(channel)] : 0.0;
  };
  read(c.q_in, &r.q_in_m3s, &r.q_in_valid);
  read(c.q_out, &r.q_out_m3s, &r.q_out_valid);
  read(c.level, &r.level_m, &r.level_valid);
  read(c.actuator, &r.actuator, &r.actuator_valid);
  read(c.actuator_position, &r.actuator_position, &r.actuator_position_valid);
  read(c.scheduling, &r.scheduling, &r.scheduling_valid);
  r.link_ok = link_ok;
  r.status_ok = status_ok;
  r.time_s = time_s;
  return r;
}

/// A write on the reach's actuator as the PLC answered it.
struct ActuatorWrite {
  bool written = false;  ///< the PLC took it
  double value = 0.0;    ///< the value written
  std::uint64_t id = 0;  ///< the id OnWriteQueued() was told for it
};

/// What a write result did to a reach.
struct ReachWriteOutcome {
  /// The PLC took the nominal setpoint the reach was restoring, in a write asked for since that
  /// restore began (restore_pending() is none now).
  bool restore_confirmed = false;
  /// The experiment guard has done its job: remove it (the caller's store owns the file).
  bool remove_guard = false;
  /// A failed write: the running experiment's abort, with the nominal to restore.
  ReachActions actions;
};

/// What one poll did to a reach, for the caller to act on and report.
struct ReachPollOutcome {
  ReachActions actions;
  /// The nominal setpoint was read from this poll (the actuator's first valid reading).
  std::optional<double> nominal_read;
  /// Which experiments have no plan around that nominal, and why (empty: all have one).
  std::string plan_error;
};

/// The per-poll decisions of one reach, shared by the daemon (live) and `canalid replay` (from a
/// log), so the two run the same code on the same samples: the nominal setpoint read from the
/// actuator's first valid value when the configuration gives none, the experiment plan around it,
/// the ReachSampleProcessor step, and the start of an on_start experiment at the first complete
/// poll. It also holds the reach's restore safety, the rules that bring the actuator back to its
/// nominal and decide when that is done:
/// - every action that restores the nominal leaves it pending until a write of that value, queued
///   since the restore began, is confirmed (OnWriteQueued, OnWriteResult), or an excitation write
///   supersedes it; each poll with the link up asks for it again (OnPoll);
/// - an excitation write needs the experiment guard durably written first (needs_guard(),
///   OnGuardPersisted(); OnGuardNotPersisted() aborts instead);
/// - the guard is removed once the nominal is confirmed with no experiment running, and kept
///   after a refused start-up (for an operator to check);
/// - after a restart that restores first, no experiment starts by itself (StartIfDue) or is
///   accepted from an operator (StartRefusal) before that restore is confirmed.
/// Every event that can change the actuator goes through this class, never the pipeline
/// directly. Pure and deterministic; allocates only when the nominal is set (every experiment's
/// plan) and when an experiment is installed in the pipeline (its record), never per poll.
class ReachController final {
 public:
  /// @throws std::invalid_argument on bad pipeline options.
  explicit ReachController(ReachControllerOptions options);

  /// Steps the reach with one poll.  The caller acts on `actions` (writes, record complete: call
  /// IdentifyRecord()) and then calls StartIfDue().  With a restore pending and the link up, the
  /// actions write its nominal when they write nothing else.
  ReachPollOutcome OnPoll(const ReachReadings& readings);
  /// Starts the on_start experiment once: after a poll with every block read, when the nominal is
  /// known, excitation_allowed() and `allowed` (the daemon is not stopping).  Returns the start's
  /// actions, or none.
  std::optional<ReachActions> StartIfDue(bool status_ok, bool allowed);

  /// Why an operator's start of experiment `name` would be refused now (empty: it would start).
  /// An empty name means the reach's only experiment (refused when it has several).
  std::string StartRefusal(std::string_view name = {}) const;
  /// Starts experiment `name` (empty: the reach's only one) now, without the other checks of
  /// StartRefusal() (an operator's command checks it first; a replay follows the live run's
  /// start). Nothing happens when the name has no plan or an experiment is running.
  ReachActions Start(std::string_view name = {});
  /// An operator's stop, or the daemon's: aborts a running experiment, restoring the nominal.
  ReachActions Stop();
  /// Its joint experiment fails (JointExperiments: a member aborted, or a partner could not start
  /// with the leader): aborts a running experiment (kJointStop), restoring the nominal.
  ReachActions StopJoint();
  /// Its joint experiment's leader completed its excitation (JointExperiments): a running
  /// experiment ends done (kJointEnd), restoring the nominal, without identification.
  ReachActions EndJoint();
  /// The link to the PLC is down between polls: aborts a running experiment.
  ReachActions OnLinkLost();
  /// The caller queued the write of the last actions to the actuator, under `id` (ids increase
  /// from one write to the next). Only a write queued since a restore began can confirm it.
  void OnWriteQueued(std::uint64_t id);
  /// The PLC's answer to a write on the reach's actuator.
  ReachWriteOutcome OnWriteResult(const ActuatorWrite& write);
  /// An excitation write in `actions` that needs the experiment guard written first.
  bool needs_guard(const ReachActions& actions) const {
    return actions.write_setpoint && !actions.restore_nominal && !guard_on_disk_;
  }
  /// The experiment guard is durably written: excitation writes may go out.
  void OnGuardPersisted() { guard_on_disk_ = true; }
  /// The experiment guard could not be written: aborts the experiment, restoring the nominal.
  ReachActions OnGuardNotPersisted();
  /// The record of a complete experiment identified (ReachSampleProcessor::IdentifyRecord).
  std::optional<IntegratorDelayIdentification> IdentifyRecord(ReachActions* actions);
  /// An operator's reset of the online estimators.
  void ResetOnlineEstimator() { pipeline_.ResetOnlineEstimator(); }

  /// Applies the start-up decision on an interrupted experiment (DecideRestart), before the first
  /// poll: adopts its nominal (installing the experiment around it; returns the plan error, empty
  /// when none), never takes a reading as the nominal when it refuses, makes its restore pending
  /// (written at the first poll with the link up), and holds experiments until that restore is
  /// confirmed.
  std::string ApplyRestart(const RestartDecision& decision);
  /// StartIfDue has started the on_start experiment (it never starts it again).
  bool on_start_done() const { return started_; }
  /// An experiment may start now (not refused at start-up, no restore pending confirmation).
  bool excitation_allowed() const { return !refused_ && !held_; }
  /// The nominal setpoint being restored and not yet confirmed by the PLC (none: nothing pending).
  const std::optional<double>& restore_pending() const { return restore_pending_; }

  /// Sets the nominal setpoint and plans every experiment around it; returns why some have no
  /// plan (each named; empty when all have one or none is configured).  The on_start experiment
  /// (else the first with a plan) is installed in the pipeline.
  std::string SetNominal(double nominal);
  /// The experiment installed in the pipeline: running, last run, or next to start by itself
  /// (empty: none has a plan).
  const std::string& experiment_name() const;

  const ReachSampleProcessor& pipeline() const { return pipeline_; }
  const ReachControllerOptions& options() const { return options_; }
  const std::string& name() const { return options_.name; }
  bool nominal_known() const { return nominal_known_; }
  double nominal() const { return nominal_; }
  /// The error of the plan installed at construction from a configured nominal (empty: none).
  const std::string& initial_plan_error() const { return initial_plan_error_; }

 private:
  /// Notes the restore `actions` ask for (pending until confirmed); returns them.
  ReachActions Track(ReachActions actions);
  /// The index of experiment `name` (empty: the only one), or why there is none.
  std::optional<std::size_t> FindExperiment(std::string_view name, std::string* problem) const;
  /// Installs experiment `index`'s plan in the pipeline (false: it has none, or one is running).
  bool Install(std::size_t index);

  ReachControllerOptions options_;
  ReachSampleProcessor pipeline_;
  bool nominal_known_ = false;
  double nominal_ = 0.0;
  bool started_ = false;
  bool refused_ = false;
  bool held_ = false;
  bool adopt_reading_ = true;
  std::optional<double> restore_pending_;
  /// The first write queued for the pending restore (none: none queued yet).
  std::optional<std::uint64_t> restore_first_write_;
  bool guard_on_disk_ = false;  ///< written by this run, or left by an interrupted one
  bool keep_guard_ = false;     ///< a refused start-up: the guard stays for an operator
  std::string initial_plan_error_;
  /// Each experiment's plan around the nominal (none: it does not fit, see SetNominal's errors).
  std::vector<std::optional<ExperimentPlan>> plans_;
  std::optional<std::size_t> installed_;  ///< the experiment in the pipeline
};

}  // namespace canalid::core
