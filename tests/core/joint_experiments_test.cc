// JointExperiments in process: a two-structure experiment as two ReachControllers, the pool's
// inflow gate (reach "gate", the leader) and its offtake (reach "offtake", a partner with no
// model), driven poll by poll as the daemon drives them. Every expectation comes from the
// contracts in joint_experiments.h, reach_controller.h and experiment.h.
#include "core/reach/joint_experiments.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::core {
namespace {

constexpr std::int64_t kSettle = 2;
constexpr std::int64_t kExcite = 12;
constexpr double kGateNominal = 1.0;
constexpr double kOfftakeNominal = 0.5;

ExperimentPlan Plan(double nominal, double amplitude, std::uint32_t seed, double level_max_m) {
  ExperimentPlan plan;
  plan.prbs.nominal = nominal;
  plan.prbs.amplitude = amplitude;
  plan.prbs.clock_period_samples = 2;
  plan.prbs.order = 3;
  plan.prbs.seed = seed;
  plan.settle_samples = kSettle;
  plan.excite_samples = kExcite;
  plan.level_min_m = 1.0;
  plan.level_max_m = level_max_m;
  plan.max_invalid_samples = 1;
  return plan;
}

// The leader: the id model of the pool, its gate's PRBS.
ReachControllerOptions Gate(std::optional<double> nominal = kGateNominal) {
  ReachControllerOptions o;
  o.name = "gate";
  o.channels = {0, 1, 2, 3};
  o.pipeline.sample_time_s = 1.0;
  o.pipeline.online_id.min_delay_samples = 1;
  o.pipeline.online_id.max_delay_samples = 3;
  o.pipeline.batch.fit.min_nk = 1;
  o.pipeline.batch.fit.max_nk = 3;
  o.nominal_setpoint = nominal;
  o.experiments = {{"gate-prbs", [](double n) { return Plan(n, 0.1, 5, 3.0); }, false}};
  return o;
}

// The partner: the offtake of the same pool, no model, a narrower level band and another seed.
ReachControllerOptions Offtake(std::optional<double> nominal = kOfftakeNominal) {
  ReachControllerOptions o;
  o.name = "offtake";
  o.channels.level = 2;
  o.channels.actuator = 4;
  o.pipeline.sample_time_s = 1.0;
  o.pipeline.online_id_enabled = false;
  o.pipeline.batch_id = false;
  o.nominal_setpoint = nominal;
  o.experiments = {{"offtake-prbs", [](double n) { return Plan(n, 0.05, 3, 2.5); }, false}};
  return o;
}

struct Written {
  std::size_t reach;
  double value;
  bool restore;
};

// The gate's experiment with the offtake's.
std::vector<JointExperiment> TwoStructures() {
  JointExperiment joint;
  joint.leader = {0, "gate-prbs"};
  joint.partners = {{1, "offtake-prbs"}};
  return {joint};
}

// The daemon's sequence on each poll: every reach's OnPoll, then every reach's StartIfDue; every
// action's writes go to the PLC (confirmed at once), a phase change goes to the joint rules, whose
// orders are acted on the same way, and a complete record is identified.
class Rig {
 public:
  Rig(ReachControllerOptions gate, ReachControllerOptions offtake)
      : gate_(std::move(gate)), offtake_(std::move(offtake)) {
    reaches_ = {&gate_, &offtake_};
    joints_ = JointExperiments(TwoStructures());
  }

  void Poll(double level = 2.0) {
    for (std::size_t r = 0; r < 2; ++r) {
      ReachReadings readings;
      readings.q_in_m3s = 1.0;
      readings.q_out_m3s = 1.0;
      readings.level_m = level;
      readings.actuator = r == 0 ? gate_actuator : offtake_actuator;
      readings.q_in_valid = readings.q_out_valid = readings.level_valid = true;
      readings.actuator_valid = true;
      readings.time_s = time_s_;
      Act(r, reaches_[r]->OnPoll(readings).actions);
    }
    for (std::size_t r = 0; r < 2; ++r) {
      const bool allowed = joints_.OnStartAllowed(reaches_, r);
      if (const auto start = reaches_[r]->StartIfDue(true, allowed)) Act(r, *start);
    }
    time_s_ += 1.0;
  }
  void Act(std::size_t r, const ReachActions& a) {
    ReachController& c = *reaches_[r];
    // As the daemon: the guard is written before the first excitation write, and removed when
    // the PLC confirms the restore with no experiment running.
    if (c.needs_guard(a)) {
      c.OnGuardPersisted();
      guard[r] = true;
    }
    if (a.write_setpoint) {
      written.push_back({r, *a.write_setpoint, a.restore_nominal});
      (r == 0 ? gate_actuator : offtake_actuator) = *a.write_setpoint;
      c.OnWriteQueued(++write_id_);
      if (c.OnWriteResult({true, *a.write_setpoint, write_id_}).remove_guard) guard[r] = false;
    }
    if (a.experiment_phase_changed) {
      for (const JointOrder& order : joints_.AfterPhaseChange(reaches_, r)) {
        why.push_back(order.why);
        Act(order.reach, order.actions);
      }
    }
    if (a.experiment_record_complete) {
      ReachActions after;
      c.IdentifyRecord(&after);
      Act(r, after);
    }
  }
  void Start(std::size_t r) { Act(r, reaches_[r]->Start()); }
  ExperimentPhase Phase(std::size_t r) const {
    return reaches_[r]->pipeline().experiment_state().phase;
  }
  AbortReason Reason(std::size_t r) const {
    return reaches_[r]->pipeline().experiment_state().abort_reason;
  }
  ReachController& reach(std::size_t r) { return *reaches_[r]; }
  JointExperiments& joints() { return joints_; }
  std::span<ReachController* const> reaches() const { return reaches_; }

  double gate_actuator = kGateNominal;
  double offtake_actuator = kOfftakeNominal;
  std::vector<Written> written;
  std::vector<std::string> why;
  std::array<bool, 2> guard{};  // each reach's experiment guard on disk

 private:
  ReachController gate_;
  ReachController offtake_;
  std::array<ReachController*, 2> reaches_{};
  JointExperiments joints_;
  std::uint64_t write_id_ = 0;
  double time_s_ = 0.0;
};

TEST(JointExperiments, TheLeadersStartStartsThePartnerAtTheSamePoll) {
  Rig rig(Gate(), Offtake());
  rig.Poll();
  rig.Start(0);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kSettling);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kSettling);
  ASSERT_EQ(rig.written.size(), 2U);
  // Each settles at its own nominal, on its own actuator.
  EXPECT_EQ(rig.written[0].reach, 0U);
  EXPECT_DOUBLE_EQ(rig.written[0].value, kGateNominal);
  EXPECT_EQ(rig.written[1].reach, 1U);
  EXPECT_DOUBLE_EQ(rig.written[1].value, kOfftakeNominal);
  EXPECT_NE(rig.why.at(0).find("started with experiment 'gate-prbs' of reach gate"),
            std::string::npos)
      << rig.why.at(0);
  // Both excite together, each with its own PRBS around its own nominal.
  for (int k = 0; k < 4; ++k) rig.Poll();
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kExciting);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kExciting);
  EXPECT_NEAR(std::abs(rig.gate_actuator - kGateNominal), 0.1, 1e-12);
  EXPECT_NEAR(std::abs(rig.offtake_actuator - kOfftakeNominal), 0.05, 1e-12);
}

TEST(JointExperiments, TheEndOfTheLeadersExcitationEndsThePartnerDoneAndRestoresIt) {
  Rig rig(Gate(), Offtake());
  rig.Poll();
  rig.Start(0);
  for (int k = 0; k < kSettle + kExcite + 2 && IsRunning(rig.Phase(0)); ++k) rig.Poll();
  EXPECT_FALSE(IsRunning(rig.Phase(0)));
  // A normal end: done with the leader, not aborted (its own PRBS would have run longer).
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kDone);
  EXPECT_EQ(rig.Reason(1), AbortReason::kNone);
  EXPECT_TRUE(rig.reach(1).pipeline().experiment_state().ended_with_joint);
  EXPECT_NE(rig.why.back().find("experiment 'gate-prbs' of reach gate is identifying"),
            std::string::npos)
      << rig.why.back();
  // Both guards were written before the excitation and are gone with the confirmed restores.
  EXPECT_FALSE(rig.guard[0]);
  EXPECT_FALSE(rig.guard[1]);
  // Its last write is its nominal, confirmed: nothing pending.
  EXPECT_DOUBLE_EQ(rig.offtake_actuator, kOfftakeNominal);
  EXPECT_FALSE(rig.reach(1).restore_pending().has_value());
  EXPECT_DOUBLE_EQ(rig.gate_actuator, kGateNominal);
  // Nothing moves either actuator afterwards.
  const std::size_t writes = rig.written.size();
  for (int k = 0; k < 5; ++k) rig.Poll();
  EXPECT_EQ(rig.written.size(), writes);
}

TEST(JointExperiments, BothGuardsAreWrittenBeforeTheExcitation) {
  Rig rig(Gate(), Offtake());
  rig.Poll();
  rig.Start(0);
  for (int k = 0; k < 4; ++k) rig.Poll();
  ASSERT_EQ(rig.Phase(1), ExperimentPhase::kExciting);
  EXPECT_TRUE(rig.guard[0]);
  EXPECT_TRUE(rig.guard[1]);
}

TEST(JointExperiments, HasOtherMemberOnlyWithAMemberOnAnotherReach) {
  JointExperiment joint;
  joint.leader = {0, "gate-prbs"};
  joint.partners.push_back({1, "offtake-prbs"});
  JointExperiment alone;  // a replay of the leader's reach alone: no partner left
  alone.leader = {2, "lonely"};
  const JointExperiments joints({joint, alone});
  EXPECT_TRUE(joints.HasOtherMember(0, "gate-prbs"));
  EXPECT_TRUE(joints.HasOtherMember(1, "offtake-prbs"));
  EXPECT_FALSE(joints.HasOtherMember(0, "offtake-prbs"));
  EXPECT_FALSE(joints.HasOtherMember(1, "gate-prbs"));
  EXPECT_FALSE(joints.HasOtherMember(2, "lonely"));
  EXPECT_FALSE(JointExperiments().HasOtherMember(0, "gate-prbs"));
}

TEST(JointExperiments, APartnersAbortStopsTheLeaderAndBothRestore) {
  Rig rig(Gate(), Offtake());
  rig.Poll();
  rig.Start(0);
  for (int k = 0; k < 4; ++k) rig.Poll();
  ASSERT_EQ(rig.Phase(0), ExperimentPhase::kExciting);
  // 2.7 m: inside the gate's band (up to 3 m), outside the offtake's (up to 2.5 m).
  rig.Poll(2.7);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kAborted);
  EXPECT_EQ(rig.Reason(1), AbortReason::kLevelOutOfBand);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kAborted);
  EXPECT_EQ(rig.Reason(0), AbortReason::kJointStop);
  EXPECT_DOUBLE_EQ(rig.gate_actuator, kGateNominal);
  EXPECT_DOUBLE_EQ(rig.offtake_actuator, kOfftakeNominal);
  EXPECT_NE(rig.why.back().find("'offtake-prbs' of reach offtake aborted (level out of band)"),
            std::string::npos)
      << rig.why.back();
}

TEST(JointExperiments, TheLeadersAbortStopsThePartner) {
  for (const bool link_lost : {false, true}) {
    Rig rig(Gate(), Offtake());
    rig.Poll();
    rig.Start(0);
    for (int k = 0; k < 3; ++k) rig.Poll();
    rig.Act(0, link_lost ? rig.reach(0).OnLinkLost() : rig.reach(0).Stop());
    EXPECT_EQ(rig.Phase(0), ExperimentPhase::kAborted);
    EXPECT_EQ(rig.Phase(1), ExperimentPhase::kAborted);
    EXPECT_EQ(rig.Reason(1), AbortReason::kJointStop);
    EXPECT_DOUBLE_EQ(rig.gate_actuator, kGateNominal);
    EXPECT_DOUBLE_EQ(rig.offtake_actuator, kOfftakeNominal);
  }
}

TEST(JointExperiments, ALeaderWhosePartnerCannotStartIsRefusedOrStopped) {
  // The offtake's nominal is read from its first reading: none yet.
  Rig rig(Gate(), Offtake(std::nullopt));
  const std::string refusal = rig.joints().StartRefusal(rig.reaches(), 0);
  EXPECT_NE(refusal.find("'offtake-prbs' on reach offtake cannot start: experiment "
                         "'offtake-prbs' waits for the nominal setpoint"),
            std::string::npos)
      << refusal;
  // Started anyway (as an on_start experiment would be): stopped at once, the partner untouched.
  rig.Start(0);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kAborted);
  EXPECT_EQ(rig.Reason(0), AbortReason::kJointStop);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kIdle);
  for (const Written& w : rig.written) EXPECT_EQ(w.reach, 0U);
  EXPECT_DOUBLE_EQ(rig.gate_actuator, kGateNominal);
  // Once its nominal is read, the joint experiment starts whole.
  rig.Poll();
  EXPECT_EQ(rig.joints().StartRefusal(rig.reaches(), 0), "");
  rig.Start(0);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kSettling);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kSettling);
}

TEST(JointExperiments, AnOnStartLeaderWaitsForItsPartner) {
  ReachControllerOptions gate = Gate();
  gate.experiments.front().start_on_start = true;
  Rig rig(gate, Offtake());
  // The partner runs on its own (an operator's start before the first complete poll).
  rig.Start(1);
  ASSERT_EQ(rig.Phase(1), ExperimentPhase::kSettling);
  EXPECT_FALSE(rig.joints().OnStartAllowed(rig.reaches(), 0));
  rig.Poll();
  rig.Poll();
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kIdle);  // waits: neither started nor stopped
  // The partner ends (here: out of its band, as it takes the poll); once every reach has taken
  // that poll, the leader starts, and the partner with it.
  const std::size_t writes = rig.written.size();
  rig.Poll(2.7);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kSettling);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kSettling);
  EXPECT_NE(rig.why.back().find("started with experiment 'gate-prbs'"), std::string::npos);
  // In order: the partner's abort restores it, then each settles at its nominal.
  ASSERT_EQ(rig.written.size(), writes + 3);
  EXPECT_EQ(rig.written[writes].reach, 1U);
  EXPECT_TRUE(rig.written[writes].restore);
  EXPECT_EQ(rig.written[writes + 1].reach, 0U);
  EXPECT_EQ(rig.written[writes + 2].reach, 1U);
  // A reach that leads nothing is never held.
  EXPECT_TRUE(rig.joints().OnStartAllowed(rig.reaches(), 1));
}

TEST(JointExperiments, APartnerStartedOnItsOwnIsNotJoint) {
  Rig rig(Gate(), Offtake());
  rig.Poll();
  rig.Start(1);
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kSettling);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kIdle);
  // The leader cannot start while its partner runs alone.
  EXPECT_NE(rig.joints().StartRefusal(rig.reaches(), 0).find("is running"), std::string::npos);
  rig.Poll(2.7);  // the partner aborts: nothing follows for the idle leader
  EXPECT_EQ(rig.Phase(1), ExperimentPhase::kAborted);
  EXPECT_EQ(rig.Phase(0), ExperimentPhase::kIdle);
  EXPECT_TRUE(rig.why.empty());
}

TEST(JointExperiments, AReachTheCallerDoesNotRunIsSkipped) {
  // `canalid replay --reach gate`: the offtake is not replayed.
  ReachController gate(Gate());
  std::array<ReachController*, 2> reaches{&gate, nullptr};
  JointExperiments joints(TwoStructures());
  EXPECT_EQ(joints.StartRefusal(reaches, 0), "");
  ReachReadings r;
  r.level_m = 2.0;
  r.q_in_valid = r.q_out_valid = r.level_valid = r.actuator_valid = true;
  r.actuator = kGateNominal;
  r.time_s = 0.0;
  gate.OnPoll(r);
  gate.Start();
  EXPECT_TRUE(joints.AfterPhaseChange(reaches, 0).empty());
  EXPECT_TRUE(joints.AfterPhaseChange(reaches, 1).empty());
  EXPECT_EQ(gate.pipeline().experiment_state().phase, ExperimentPhase::kSettling);
}

}  // namespace
}  // namespace canalid::core
