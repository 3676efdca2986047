#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/reach/reach_controller.h"

namespace canalid::core {

/// An experiment of one reach that runs experiments of other reaches with it. The two-structure
/// experiment of a pool is one: a PRBS on its inflow gate (the leader) and a second, uncorrelated
/// PRBS on its offtake or downstream structure (a partner), so that its outflow moves on its own
/// and the IDZ model's p22 comes from the data (docs/closed-loop.md). Each actuator is the
/// actuator of its own reach, with that reach's limits, rate, level band, guard and restore.
/// Reaches are indices into the caller's list of controllers.
struct JointExperiment {
  struct Member {
    std::size_t reach = 0;
    std::string experiment;
  };
  Member leader;
  std::vector<Member> partners;  ///< each on another reach than the leader's
};

/// What the joint rules did to a reach other than the one whose phase changed: the actions to act
/// on as on the reach's own (writes, guard, publication; their phase change is passed back to
/// AfterPhaseChange like any other), and why, for the log.
struct JointOrder {
  std::size_t reach = 0;
  ReachActions actions;
  std::string why;
};

/// The rules of joint experiments, shared by the daemon and `canalid replay`, which run them on the
/// same events:
/// - the leader's experiment starts only with all its partners: StartRefusal() includes theirs,
///   and when the leader starts (settling or exciting from another phase) with a partner unable to
///   start, the leader stops at once (kJointStop) and nothing else moves;
/// - when the leader starts, each partner's experiment starts with it, at the same poll;
/// - when the leader's excitation is over (it leaves exciting to identify its record), the
///   partners still running end with it (kJointEnd: done, not identified): they move their
///   actuators for the leader's record only;
/// - when the leader aborts, the partners still running stop (kJointStop: aborted);
/// - when a partner aborts while the leader runs, the leader and the other partners stop.
/// The rules only add starts, ends and stops: every actuator keeps its own reach's safety rules,
/// and every stop restores that actuator's nominal through its own ReachController. A partner's
/// experiment started on its own (an operator's command) is not joint: nothing follows from it.
/// The rules act on the poll's phase changes in the order the caller passes them (the daemon and
/// the replay: reach by reach, in configuration order). When the leader's excitation ends on the
/// poll where a partner aborts, the first one handled decides: a partner handled after the
/// leader has already ended done; one handled before aborts and stops the leader.
/// Deterministic; allocates when a phase changes (the orders) and while OnStartAllowed finds a
/// partner refusing, never on a poll otherwise.
class JointExperiments final {
 public:
  JointExperiments() = default;
  explicit JointExperiments(std::vector<JointExperiment> joints);

  /// Why starting experiment `name` (empty: the reach's only one) of `reach` would be refused now:
  /// its own refusal, else that of a partner (named); empty when all would start. A null entry of
  /// `reaches` is a reach the caller does not run (a replay of one reach): it refuses nothing.
  std::string StartRefusal(std::span<ReachController* const> reaches, std::size_t reach,
                           std::string_view name = {}) const;
  /// Whether the on_start experiment of `reach` may start now as far as its joint experiment goes:
  /// every partner would start (true when it leads none). The caller passes it to
  /// ReachController::StartIfDue, so that an on_start experiment waits for a partner that is busy
  /// or holding a restart's restore instead of being started and stopped at once. A partner that
  /// can never start (no room around its nominal, logged at start-up) holds it for good. Builds
  /// a partner's refusal text while it refuses: callers skip it once the on_start experiment ran
  /// (ReachController::on_start_done).
  bool OnStartAllowed(std::span<ReachController* const> reaches, std::size_t reach) const;
  /// Whether experiment `experiment` of `reach` is in a joint experiment with a member on another
  /// reach: then that member's end or abort reaches it through AfterPhaseChange (a replay of one
  /// reach has no joint experiment with the reaches it does not run).
  bool HasOtherMember(std::size_t reach, std::string_view experiment) const;
  /// After actions of `reach` that changed its experiment's phase: the starts and stops the joint
  /// rules ask of other reaches (empty: none).
  std::vector<JointOrder> AfterPhaseChange(std::span<ReachController* const> reaches,
                                           std::size_t reach);

 private:
  /// How the other members of a joint experiment end.
  enum class Ending : std::uint8_t {
    kDone,     ///< ReachController::EndJoint: done with the leader
    kAborted,  ///< ReachController::StopJoint: aborted with it
  };
  /// Ends (`how`) every member of joint `j` but `except` that is still running, with `why`.
  void EndOthers(std::span<ReachController* const> reaches, std::size_t j, std::size_t except,
                 Ending how, const std::string& why, std::vector<JointOrder>* orders) const;

  std::vector<JointExperiment> joints_;
  std::vector<char> active_;  ///< per joint: its leader started it and it has not ended
};

}  // namespace canalid::core
