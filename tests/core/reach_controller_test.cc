// ReachController in process: the nominal setpoint, the on_start experiment, the PRBS it asks to
// write, the safety rules on bad polls, the restart guard, and determinism.  Every expectation
// below comes from the headers' contracts (reach_controller.h, reach_sample_processor.h,
// experiment.h, experiment_guard.h, prbs.h), never from a run of the code.
#include "core/reach/reach_controller.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/experiment/experiment_guard.h"

namespace canalid::core {
namespace {

// Small numbers: Ts = 1 s, delay bank 1..5 samples, PRBS of order 3 (period 7 clocks) held
// 2 samples per clock, two periods of excitation after 3 samples of settling.
constexpr double kTs = 1.0;
constexpr double kSetpointMin = 0.5;
constexpr double kSetpointMax = 1.5;
constexpr double kAmplitude = 0.1;
constexpr int kClock = 2;
constexpr int kOrder = 3;
constexpr std::uint32_t kSeed = 5;  // 0b101: a(t-1) = 1, a(t-2) = 0, a(t-3) = 1
constexpr std::int64_t kSettle = 3;
constexpr std::int64_t kExcite = std::int64_t{2} * 7 * kClock;
constexpr int kMaxInvalid = 2;
constexpr double kMaxGapS = 2.5;
constexpr double kLevelMin = 1.0;
constexpr double kLevelMax = 3.0;

// One period of the order-3 m-sequence from seed 0b101, by hand from prbs.h: taps {3, 2}, i.e.
// a(t) = a(t-3) XOR a(t-2), history a(-1) = 1, a(-2) = 0, a(-3) = 1:
//   a0 = 1^0 = 1, a1 = 0^1 = 1, a2 = 1^1 = 0, a3 = 1^1 = 0, a4 = 1^0 = 1, a5 = 0^0 = 0,
//   a6 = 0^1 = 1 (then a7 = a0): four +1, three -1, as an m-sequence of order 3 must have.
constexpr std::array<int, 7> kSequence = {+1, +1, -1, -1, +1, -1, +1};

// u(k) = nominal + amplitude s(floor(k / clock)) (prbs.h, plain mode).
double Prbs(double nominal, std::int64_t k) {
  return nominal + kAmplitude * kSequence[static_cast<std::size_t>((k / kClock) % 7)];
}

// As the daemon's BuildExperimentPlan: a plan around the nominal, refused when nominal +-
// amplitude leaves the actuator's [min, max].
ExperimentPlan PlanFor(double nominal) {
  if (!(nominal - kAmplitude >= kSetpointMin && nominal + kAmplitude <= kSetpointMax)) {
    throw std::invalid_argument("nominal " + std::to_string(nominal) +
                                " leaves no room for the PRBS");
  }
  ExperimentPlan plan;
  plan.prbs.nominal = nominal;
  plan.prbs.amplitude = kAmplitude;
  plan.prbs.clock_period_samples = kClock;
  plan.prbs.order = kOrder;
  plan.prbs.seed = kSeed;
  plan.settle_samples = kSettle;
  plan.excite_samples = kExcite;
  plan.level_min_m = kLevelMin;
  plan.level_max_m = kLevelMax;
  plan.max_invalid_samples = kMaxInvalid;
  plan.max_sample_gap_s = kMaxGapS;
  plan.Validate();
  return plan;
}

ReachControllerOptions Options(std::optional<double> nominal, bool on_start = true) {
  ReachControllerOptions o;
  o.name = "pool1";
  o.channels = {0, 1, 2, 3};
  o.pipeline.sample_time_s = kTs;
  o.pipeline.online_id_enabled = true;
  o.pipeline.online_id.min_delay_samples = 1;
  o.pipeline.online_id.max_delay_samples = 5;
  o.pipeline.batch.fit.min_nk = 1;
  o.pipeline.batch.fit.max_nk = 5;
  o.nominal_setpoint = nominal;
  o.experiments = {{"pool1-prbs", PlanFor, on_start}};
  return o;
}

// An integrator-delay pool fed by the actuator (its setpoint is the inflow, m3/s), drained at
// 1 m3/s: level(k+1) = level(k) + Ts / A (q_in(k - 2) - q_out), A = 200 m^2, i.e. the ID model
// y(k) - y(k-1) = b (q_in(k - nk) - q_out) with nk = 3, inside the bank 1..5.  The PLC
// echoes the last setpoint written as the actuator's reading.  Polls every Ts from t = 100 s.
class Pool {
 public:
  explicit Pool(double actuator) : actuator_(actuator), inflow_(kDelay, actuator) {}

  // The next complete poll (every channel valid, every block read).
  ReachReadings Poll() {
    ReachReadings r;
    r.q_in_m3s = actuator_;
    r.q_out_m3s = kOutflow;
    r.level_m = level_;
    r.actuator = actuator_;
    r.q_in_valid = r.q_out_valid = r.level_valid = r.actuator_valid = true;
    r.time_s = time_s_;
    inflow_.push_back(actuator_);
    level_ += kTs / kArea * (inflow_.front() - kOutflow);
    inflow_.pop_front();
    time_s_ += kTs;
    return r;
  }
  void Write(double setpoint) { actuator_ = setpoint; }
  // A poll taken later than usual (the next is then due Ts after it).
  void Skip(double seconds) { time_s_ += seconds; }
  double actuator() const { return actuator_; }

 private:
  static constexpr double kArea = 200.0;
  static constexpr int kDelay = 2;  // q_in samples in flight
  static constexpr double kOutflow = 1.0;
  double actuator_;
  double level_ = 2.0;
  double time_s_ = 100.0;
  std::deque<double> inflow_;
};

// A setpoint the controller asked for, and the poll it was asked at.
struct Write {
  int poll = 0;
  double value = 0.0;
  bool restore = false;
  bool record_complete = false;
};

// Runs the daemon's per-poll sequence: OnPoll, act on its writes, then StartIfDue and act on its
// writes. Each write is queued under the next id (OnWriteQueued); the pool takes it at once and,
// while `confirm_writes`, the PLC's confirmation goes back to the controller at once
// (OnWriteResult).
class Harness {
 public:
  explicit Harness(ReachControllerOptions options, double actuator = 1.0)
      : controller(std::move(options)), pool(actuator) {}

  ReachPollOutcome Step(ReachReadings r, bool allowed = true) {
    ReachPollOutcome outcome = controller.OnPoll(r);
    Take(outcome.actions);
    if (const auto start = controller.StartIfDue(r.status_ok, allowed)) {
      started_at.push_back(polls);
      Take(*start);
    }
    ++polls;
    return outcome;
  }
  ReachPollOutcome Step() { return Step(pool.Poll()); }
  void Steps(int n) {
    for (int i = 0; i < n; ++i) Step();
  }
  ExperimentPhase phase() const { return controller.pipeline().experiment_state().phase; }
  AbortReason reason() const { return controller.pipeline().experiment_state().abort_reason; }

  ReachController controller;
  Pool pool;
  std::vector<Write> writes;
  std::vector<int> started_at;
  int polls = 0;
  bool confirm_writes = true;
  std::uint64_t write_id = 0;  ///< the last write's

 private:
  void Take(const ReachActions& a) {
    if (!a.write_setpoint) {
      EXPECT_FALSE(a.restore_nominal) << "a restore with nothing to write, poll " << polls;
      return;
    }
    writes.push_back({polls, *a.write_setpoint, a.restore_nominal, a.experiment_record_complete});
    pool.Write(*a.write_setpoint);
    controller.OnWriteQueued(++write_id);
    if (confirm_writes) {
      const ReachWriteOutcome outcome =
          controller.OnWriteResult({true, *a.write_setpoint, write_id});
      EXPECT_FALSE(outcome.actions.write_setpoint) << "a written setpoint aborted, poll " << polls;
    }
  }
};

// A poll whose level block was not read (failed status): the level comes back invalid.
ReachReadings LevelBlockFailed(ReachReadings r) {
  r.status_ok = false;
  r.level_valid = false;
  r.level_m = 0.0;
  return r;
}

void ExpectInsideLimits(const std::vector<Write>& writes) {
  for (const Write& w : writes) {
    EXPECT_GE(w.value, kSetpointMin) << "poll " << w.poll;
    EXPECT_LE(w.value, kSetpointMax) << "poll " << w.poll;
  }
}

// ----- the nominal setpoint ---------------------------------------------------------------------

TEST(ReachControllerNominal, TheConfiguredNominalIsTheNominalAndNoReadingMovesIt) {
  ReachController c(Options(0.9));
  EXPECT_TRUE(c.nominal_known());
  EXPECT_EQ(c.nominal(), 0.9);
  EXPECT_EQ(c.initial_plan_error(), "");
  ASSERT_TRUE(c.pipeline().experiment_plan());
  EXPECT_EQ(c.pipeline().experiment_plan()->prbs.nominal, 0.9);

  Pool pool(1.2);  // the actuator reads something else
  const ReachPollOutcome first = c.OnPoll(pool.Poll());
  EXPECT_FALSE(first.nominal_read);
  EXPECT_EQ(first.plan_error, "");
  EXPECT_EQ(c.nominal(), 0.9);
  EXPECT_EQ(c.pipeline().experiment_plan()->prbs.nominal, 0.9);
}

TEST(ReachControllerNominal, AConfiguredNominalWithNoRoomForThePrbsIsAnInitialPlanError) {
  ReachController c(Options(1.45));  // 1.45 + 0.1 > 1.5
  EXPECT_TRUE(c.nominal_known());
  EXPECT_EQ(c.nominal(), 1.45);
  EXPECT_NE(c.initial_plan_error(), "");
  EXPECT_FALSE(c.pipeline().experiment_plan());
}

TEST(ReachControllerNominal, ReadFromTheFirstValidActuatorReadingNeverAnInvalidOne) {
  ReachController c(Options(std::nullopt, /*on_start=*/false));
  EXPECT_FALSE(c.nominal_known());
  EXPECT_FALSE(c.pipeline().experiment_plan());
  Pool pool(1.0);

  // The actuator channel flagged invalid, with a value in it: not a nominal.
  ReachReadings invalid = pool.Poll();
  invalid.actuator = 0.7;
  invalid.actuator_valid = false;
  EXPECT_FALSE(c.OnPoll(invalid).nominal_read);
  EXPECT_FALSE(c.nominal_known());

  // A disconnected poll: nothing valid, nothing read.
  ReachReadings down;
  down.link_ok = false;
  down.status_ok = false;
  down.actuator = 0.8;
  down.time_s = 102.0;
  EXPECT_FALSE(c.OnPoll(down).nominal_read);
  EXPECT_FALSE(c.nominal_known());
  EXPECT_FALSE(c.pipeline().experiment_plan());

  // The first valid reading is the nominal, and the plan is centred on it.
  pool.Write(1.1);
  const ReachPollOutcome first = c.OnPoll(pool.Poll());
  ASSERT_TRUE(first.nominal_read);
  EXPECT_EQ(*first.nominal_read, 1.1);
  EXPECT_EQ(first.plan_error, "");
  EXPECT_TRUE(c.nominal_known());
  EXPECT_EQ(c.nominal(), 1.1);
  ASSERT_TRUE(c.pipeline().experiment_plan());
  EXPECT_EQ(c.pipeline().experiment_plan()->prbs.nominal, 1.1);

  // Never read again: later readings do not move it.
  for (const double later : {1.25, 0.6, 1.1}) {
    pool.Write(later);
    const ReachPollOutcome outcome = c.OnPoll(pool.Poll());
    EXPECT_FALSE(outcome.nominal_read);
    EXPECT_EQ(outcome.plan_error, "");
    EXPECT_EQ(c.nominal(), 1.1);
    EXPECT_EQ(c.pipeline().experiment_plan()->prbs.nominal, 1.1);
  }
}

TEST(ReachControllerNominal, ReadReachMapsChannelsAndTheirValidity) {
  const ReachChannels channels{4, 1, 2, 0};  // q_in, q_out, level, actuator
  const std::array<double, 5> values = {1.3, 0.9, 2.2, 99.0, 1.05};
  std::array<bool, 5> valid = {false, true, true, true, true};
  auto is_valid = [&](std::size_t i) { return valid[i]; };

  ReachReadings r = ReadReach(channels, values, is_valid, true, false, 7.0);
  EXPECT_EQ(r.q_in_m3s, 1.05);
  EXPECT_EQ(r.q_out_m3s, 0.9);
  EXPECT_EQ(r.level_m, 2.2);
  EXPECT_TRUE(r.q_in_valid && r.q_out_valid && r.level_valid);
  EXPECT_FALSE(r.actuator_valid);
  EXPECT_FALSE(r.status_ok);
  EXPECT_EQ(r.time_s, 7.0);

  ReachController c(Options(std::nullopt, false));
  EXPECT_FALSE(c.OnPoll(r).nominal_read);  // 1.3 sits in an invalid channel
  EXPECT_FALSE(c.nominal_known());

  valid[0] = true;
  r = ReadReach(channels, values, is_valid, true, true, 8.0);
  const ReachPollOutcome outcome = c.OnPoll(r);
  ASSERT_TRUE(outcome.nominal_read);
  EXPECT_EQ(*outcome.nominal_read, 1.3);
  EXPECT_EQ(c.nominal(), 1.3);
}

TEST(ReachControllerNominal, AReadNominalWithNoRoomForThePrbsIsKeptWithoutAnExperiment) {
  Harness h(Options(std::nullopt), /*actuator=*/1.45);
  const ReachPollOutcome first = h.Step();
  ASSERT_TRUE(first.nominal_read);
  EXPECT_EQ(*first.nominal_read, 1.45);
  EXPECT_NE(first.plan_error, "");
  EXPECT_FALSE(h.controller.pipeline().experiment_plan());
  // The reach is never excited, and a later reading that would leave room is not taken.
  h.pool.Write(1.0);
  for (int i = 0; i < 5; ++i) {
    const ReachPollOutcome later = h.Step();
    EXPECT_FALSE(later.nominal_read);
    EXPECT_EQ(later.plan_error, "");
  }
  EXPECT_EQ(h.controller.nominal(), 1.45);
  EXPECT_TRUE(h.writes.empty());
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdle);
}

// ----- the on_start experiment ------------------------------------------------------------------

TEST(ReachControllerOnStart, StartsAtTheFirstCompletePollAndNotBefore) {
  Harness h(Options(1.0));
  // Some block of the poll was not read.
  h.Step(LevelBlockFailed(h.pool.Poll()));
  // Disconnected.
  ReachReadings down;
  down.link_ok = false;
  down.status_ok = false;
  down.time_s = 101.0;
  h.pool.Skip(kTs);
  h.Step(down);
  // Every block read, but the daemon is stopping.
  h.Step(h.pool.Poll(), /*allowed=*/false);
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.writes.empty());
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdle);

  // The first complete poll starts it: settling begins at the nominal.
  h.Step();
  ASSERT_EQ(h.started_at, std::vector<int>{3});
  ASSERT_EQ(h.writes.size(), 1U);
  EXPECT_EQ(h.writes[0].value, 1.0);
  EXPECT_TRUE(h.writes[0].restore);
  EXPECT_EQ(h.phase(), ExperimentPhase::kSettling);

  // Once only: later complete polls, and the end of the experiment, start nothing.
  h.Steps(static_cast<int>(kSettle + kExcite) + 5);
  EXPECT_EQ(h.started_at, std::vector<int>{3});
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdentifying);
}

TEST(ReachControllerOnStart, WaitsForTheNominalWhenNoneIsConfigured) {
  Harness h(Options(std::nullopt));
  ReachReadings r = h.pool.Poll();
  r.actuator_valid = false;  // every block read, but the actuator's value is not valid
  h.Step(r);
  EXPECT_FALSE(h.controller.nominal_known());
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.writes.empty());

  // The actuator valid but a block failed: the nominal is read, the start waits.
  r = LevelBlockFailed(h.pool.Poll());
  EXPECT_TRUE(h.Step(r).nominal_read);
  EXPECT_TRUE(h.started_at.empty());

  h.Step();
  EXPECT_EQ(h.started_at, std::vector<int>{2});
  ASSERT_EQ(h.writes.size(), 1U);
  EXPECT_EQ(h.writes[0].value, 1.0);
}

TEST(ReachControllerOnStart, AManualExperimentNeverStartsByItself) {
  Harness h(Options(1.0, /*on_start=*/false));
  h.Steps(20);
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.writes.empty());
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdle);
}

// ----- several experiments on one reach ---------------------------------------------------------

// PlanFor as a step of `amplitude` held `hold` samples: a second experiment told from the first by
// its writes (nominal + amplitude, never nominal - amplitude).
ExperimentPlan StepFor(double nominal, double amplitude, std::int64_t hold) {
  if (nominal + amplitude > kSetpointMax) throw std::invalid_argument("no room for the step");
  ExperimentPlan plan = PlanFor(nominal);
  plan.prbs.amplitude = amplitude;
  plan.step_hold_samples = hold;
  plan.excite_samples = 2 * hold;
  return plan;
}

// Options(nominal) with a PRBS "prbs" and a step "step" (+0.2 for 4 samples, then 4 back).
ReachControllerOptions TwoExperiments(std::optional<double> nominal, bool step_on_start) {
  ReachControllerOptions o = Options(nominal, /*on_start=*/false);
  o.experiments = {{"prbs", PlanFor, false},
                   {"step", [](double n) { return StepFor(n, 0.2, 4); }, step_on_start}};
  return o;
}

TEST(ReachControllerExperiments, TheOnStartExperimentIsTheOneThatStartsNotTheFirst) {
  Harness h(TwoExperiments(1.0, /*step_on_start=*/true));
  EXPECT_EQ(h.controller.experiment_name(), "step");
  h.Steps(static_cast<int>(kSettle) + 9);
  ASSERT_EQ(h.started_at, std::vector<int>{0});
  // Settling at 1.0, then 4 samples at 1.2 and 4 back at 1.0, then the restore: a step, no PRBS.
  ASSERT_GE(h.writes.size(), 3U);
  EXPECT_EQ(h.writes.front().value, 1.0);
  int high = 0;
  for (const Write& w : h.writes) {
    EXPECT_TRUE(w.value == 1.0 || std::abs(w.value - 1.2) < 1e-12) << "poll " << w.poll;
    high += w.value > 1.1 ? 1 : 0;
  }
  EXPECT_EQ(high, 4);
  const auto first_high =
      std::find_if(h.writes.begin(), h.writes.end(), [](const Write& w) { return w.value > 1.1; });
  EXPECT_EQ(first_high->poll, kSettle);
  EXPECT_TRUE(h.writes.back().record_complete);
  EXPECT_EQ(h.controller.pipeline().recorded_samples(), 8);
}

TEST(ReachControllerExperiments, AnOperatorNamesTheExperimentAndAnUnknownNameIsRefused) {
  Harness h(TwoExperiments(1.0, /*step_on_start=*/false));
  h.Steps(2);
  EXPECT_TRUE(h.started_at.empty());
  // With two experiments an unnamed start is ambiguous; an unknown name is no experiment.
  EXPECT_EQ(h.controller.StartRefusal(), "name the experiment to start ('prbs', 'step')");
  EXPECT_EQ(h.controller.StartRefusal("flush"), "no experiment 'flush' for this reach");
  // A name from a command is shown printable (no log line injection).
  EXPECT_EQ(h.controller.StartRefusal("a\nb"), "no experiment 'a?b' for this reach");
  EXPECT_FALSE(h.controller.Start("flush").write_setpoint);
  EXPECT_FALSE(h.controller.Start().write_setpoint);
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdle);

  // "step" by name, although "prbs" comes first.
  EXPECT_EQ(h.controller.StartRefusal("step"), "");
  const ReachActions start = h.controller.Start("step");
  ASSERT_TRUE(start.write_setpoint);
  EXPECT_EQ(h.controller.experiment_name(), "step");
  h.Steps(static_cast<int>(kSettle) + 1);
  EXPECT_NEAR(h.writes.back().value, 1.2, 1e-12);
  // While it runs, no other experiment starts, and neither does it again.
  EXPECT_EQ(h.controller.StartRefusal("prbs"), "experiment 'step' is running");
  EXPECT_EQ(h.controller.StartRefusal("step"), "experiment 'step' is running");
  EXPECT_FALSE(h.controller.Start("prbs").write_setpoint);
  EXPECT_EQ(h.controller.experiment_name(), "step");

  // Stopped, "prbs" may start: its first exciting write is nominal +- the PRBS amplitude.
  h.controller.Stop();
  EXPECT_EQ(h.controller.StartRefusal("prbs"), "");
  ASSERT_TRUE(h.controller.Start("prbs").write_setpoint);
  EXPECT_EQ(h.controller.experiment_name(), "prbs");
  const std::size_t before = h.writes.size();
  h.Steps(static_cast<int>(kSettle) + 1);
  ASSERT_GT(h.writes.size(), before);
  EXPECT_NEAR(std::abs(h.writes.back().value - 1.0), kAmplitude, 1e-12);
}

TEST(ReachControllerExperiments, AnOnStartExperimentWithoutRoomNeverStartsNorWrites) {
  // Around 1.35 the on_start step (+0.2) leaves [0.5, 1.5]: nothing starts by itself, and a start
  // by its name (as a replay's, which skips StartRefusal) writes nothing.
  Harness h(TwoExperiments(1.35, /*step_on_start=*/true));
  h.Steps(5);
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.writes.empty());
  EXPECT_FALSE(h.controller.Start("step").write_setpoint);
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdle);
}

TEST(ReachControllerExperiments, AStartWhileIdentifyingChangesNothing) {
  Harness h(TwoExperiments(1.0, /*step_on_start=*/true));
  h.Steps(static_cast<int>(kSettle) + 9);
  ASSERT_EQ(h.phase(), ExperimentPhase::kIdentifying);
  EXPECT_EQ(h.controller.StartRefusal("prbs"), "experiment 'step' is running");
  EXPECT_FALSE(h.controller.Start("prbs").write_setpoint);
  EXPECT_FALSE(h.controller.Start("step").write_setpoint);
  EXPECT_EQ(h.controller.experiment_name(), "step");
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdentifying);
  EXPECT_EQ(h.controller.pipeline().recorded_samples(), 8);
}

TEST(ReachControllerExperiments, AnExperimentWithoutRoomIsNamedAndTheOtherStillRuns) {
  // Around 1.35 the step (+0.2) leaves [0.5, 1.5]; the PRBS (+-0.1) fits.
  ReachController c(TwoExperiments(1.35, /*step_on_start=*/false));
  EXPECT_NE(c.initial_plan_error().find("experiment 'step': "), std::string::npos)
      << c.initial_plan_error();
  EXPECT_EQ(c.initial_plan_error().find("'prbs'"), std::string::npos) << c.initial_plan_error();
  EXPECT_EQ(c.experiment_name(), "prbs");
  EXPECT_NE(c.StartRefusal("step").find("has no room"), std::string::npos)
      << c.StartRefusal("step");
  EXPECT_EQ(c.StartRefusal("prbs"), "");
}

// ----- the setpoints of a complete experiment ---------------------------------------------------

// Start at poll 0: settling writes the nominal; the kSettle-th settling sample (poll kSettle) asks
// for u(0); each exciting sample records and asks for the next value, u(1)..u(kExcite - 1); the
// kExcite-th exciting sample (poll kSettle + kExcite) completes the record and restores the
// nominal (experiment.h).
void ExpectOneExperiment(const Harness& h, double nominal) {
  ASSERT_EQ(h.writes.size(), static_cast<std::size_t>(kExcite + 2));
  EXPECT_EQ(h.writes.front().poll, 0);
  EXPECT_EQ(h.writes.front().value, nominal);
  EXPECT_TRUE(h.writes.front().restore);
  for (std::int64_t k = 0; k < kExcite; ++k) {
    const Write& w = h.writes[static_cast<std::size_t>(k + 1)];
    EXPECT_EQ(w.poll, kSettle + k) << "u(" << k << ")";
    EXPECT_NEAR(w.value, Prbs(nominal, k), 1e-12) << "u(" << k << ")";
    EXPECT_NEAR(std::abs(w.value - nominal), kAmplitude, 1e-12) << "u(" << k << ")";
    EXPECT_FALSE(w.restore);
    EXPECT_FALSE(w.record_complete);
  }
  const Write& end = h.writes.back();
  EXPECT_EQ(end.poll, kSettle + kExcite);
  EXPECT_EQ(end.value, nominal);
  EXPECT_TRUE(end.restore);
  EXPECT_TRUE(end.record_complete);
  ExpectInsideLimits(h.writes);
}

TEST(ReachControllerExperiment, WritesThePlansPrbsAroundTheNominalInsideTheLimitsThenRestores) {
  Harness h(Options(std::nullopt), /*actuator=*/1.0);
  h.Steps(static_cast<int>(kSettle + kExcite) + 1);
  EXPECT_EQ(h.started_at, std::vector<int>{0});
  ExpectOneExperiment(h, 1.0);
  EXPECT_EQ(h.phase(), ExperimentPhase::kIdentifying);
  EXPECT_EQ(h.controller.pipeline().recorded_samples(), kExcite);
  // Over the two periods each +1 and -1 clock holds kClock samples: 8 + 6 per period.
  int high = 0;
  for (std::size_t i = 1; i + 1 < h.writes.size(); ++i) high += h.writes[i].value > 1.0 ? 1 : 0;
  EXPECT_EQ(high, 2 * 4 * kClock);

  // Nothing more is written while the record waits for identification.
  const std::size_t written = h.writes.size();
  h.Steps(3);
  EXPECT_EQ(h.writes.size(), written);
}

TEST(ReachControllerExperiment, APlantWithAnIdModelInsideTheBankEndsDone) {
  Harness h(Options(1.0));
  h.Steps(static_cast<int>(kSettle + kExcite) + 1);
  ASSERT_EQ(h.phase(), ExperimentPhase::kIdentifying);
  ReachActions done;
  const auto result = h.controller.IdentifyRecord(&done);
  ASSERT_TRUE(result);
  EXPECT_EQ(h.controller.pipeline().identification_problem(), "");
  EXPECT_EQ(h.phase(), ExperimentPhase::kDone);
  EXPECT_EQ(result->fit.model.nk, 3);
  EXPECT_NEAR(result->fit.model.area_m2(), 200.0, 2.0);
  EXPECT_FALSE(done.write_setpoint);  // the nominal was restored at the end of the excitation
}

TEST(ReachControllerExperiment, AStopRestoresTheNominal) {
  Harness h(Options(1.0));
  h.Steps(static_cast<int>(kSettle) + 4);
  ASSERT_EQ(h.phase(), ExperimentPhase::kExciting);
  EXPECT_NE(h.pool.actuator(), 1.0);
  const ReachActions stop = h.controller.Stop();
  ASSERT_TRUE(stop.write_setpoint);
  EXPECT_EQ(*stop.write_setpoint, 1.0);
  EXPECT_TRUE(stop.restore_nominal);
  EXPECT_EQ(h.reason(), AbortReason::kOperatorStop);
}

// ----- bad polls during an experiment -----------------------------------------------------------

// Runs to the middle of the excitation: kSettle settling polls and 4 exciting ones after start.
Harness Exciting(std::optional<double> nominal = 1.0) {
  Harness h(Options(nominal));
  h.Steps(static_cast<int>(kSettle) + 4);
  EXPECT_EQ(h.phase(), ExperimentPhase::kExciting);
  return h;
}

TEST(ReachControllerBadPolls, FailedPollsAreToleratedUpToMaxInvalidSamplesThenAbort) {
  Harness h = Exciting();
  const std::size_t before = h.writes.size();
  // kMaxInvalid failed polls in a row: tolerated, the PRBS goes on.
  for (int i = 0; i < kMaxInvalid; ++i) {
    h.Step(LevelBlockFailed(h.pool.Poll()));
    EXPECT_EQ(h.phase(), ExperimentPhase::kExciting);
    ASSERT_EQ(h.writes.size(), before + static_cast<std::size_t>(i) + 1);
    EXPECT_FALSE(h.writes.back().restore);
    EXPECT_NEAR(h.writes.back().value, Prbs(1.0, 4 + i), 1e-12);
  }
  // One more: abort, and the nominal is asked for in the same poll.
  h.Step(LevelBlockFailed(h.pool.Poll()));
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kSensorInvalid);
  ASSERT_EQ(h.writes.size(), before + kMaxInvalid + 1);
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);
  EXPECT_FALSE(h.writes.back().record_complete);
  // Aborted is final: good polls write nothing more, and on_start does not start it again.
  h.Steps(5);
  EXPECT_EQ(h.writes.size(), before + kMaxInvalid + 1);
  EXPECT_EQ(h.started_at, std::vector<int>{0});
  ExpectInsideLimits(h.writes);
}

TEST(ReachControllerBadPolls, AnInvalidFlowCountsAsAnInvalidSample) {
  Harness h = Exciting();
  for (int i = 0; i <= kMaxInvalid; ++i) {
    ReachReadings r = h.pool.Poll();
    r.q_in_valid = false;  // the flows feed the record too
    h.Step(r);
  }
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kSensorInvalid);
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);
}

TEST(ReachControllerBadPolls, AValidPollEndsTheRunOfInvalidOnes) {
  Harness h = Exciting();
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < kMaxInvalid; ++i) h.Step(LevelBlockFailed(h.pool.Poll()));
    h.Step();
  }
  EXPECT_EQ(h.phase(), ExperimentPhase::kExciting);
  for (const Write& w : h.writes) EXPECT_TRUE(w.poll == 0 || !w.restore) << "poll " << w.poll;
}

TEST(ReachControllerBadPolls, ABlockOfOtherChannelsFailingDoesNotCountAgainstTheReach) {
  // The safety rules look at the reach's own values (experiment.h): a failed block that holds
  // none of them leaves the experiment running.
  Harness h = Exciting();
  for (int i = 0; i <= kMaxInvalid + 1; ++i) {
    ReachReadings r = h.pool.Poll();
    r.status_ok = false;
    h.Step(r);
  }
  EXPECT_EQ(h.phase(), ExperimentPhase::kExciting);
  EXPECT_FALSE(h.writes.back().restore);
}

TEST(ReachControllerBadPolls, ALevelThatStaysInvalidNeverSeesAPrbsWrite) {
  // Every block read but the level flagged invalid from the first poll on: whether or not the
  // on_start experiment starts on such polls, the invalid run aborts it within kMaxInvalid + 1
  // samples, before the kSettle-th settling sample could ask for the first PRBS value.
  static_assert(kMaxInvalid + 1 <= kSettle);
  Harness h(Options(1.0));
  for (int i = 0; i < static_cast<int>(kSettle + kExcite); ++i) {
    ReachReadings r = h.pool.Poll();
    r.level_valid = false;
    h.Step(r);
  }
  EXPECT_NE(h.phase(), ExperimentPhase::kExciting);
  for (const Write& w : h.writes) {
    EXPECT_EQ(w.value, 1.0) << "poll " << w.poll;
    EXPECT_TRUE(w.restore) << "poll " << w.poll;
  }
}

TEST(ReachControllerBadPolls, ADisconnectedPollAbortsAtOnce) {
  Harness h = Exciting();
  ReachReadings down;
  down.link_ok = false;
  down.status_ok = false;
  down.time_s = h.pool.Poll().time_s;
  h.Step(down);
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kLinkLost);
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);
}

TEST(ReachControllerBadPolls, AGapLongerThanMaxSampleGapAborts) {
  Harness h = Exciting();
  // One poll missed: 2 s between samples, inside the 2.5 s bound.
  h.pool.Skip(kTs);
  h.Step();
  EXPECT_EQ(h.phase(), ExperimentPhase::kExciting);
  // 3 s: beyond it.
  h.pool.Skip(2 * kTs);
  h.Step();
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kSampleGap);
  EXPECT_EQ(h.controller.pipeline().experiment_state().sample_gap_s, 3.0);
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);
  ExpectInsideLimits(h.writes);
}

TEST(ReachControllerBadPolls, AGapRightAfterTheStartAborts) {
  // The start takes the time of the poll it follows: the first settling sample must follow it
  // within the bound.
  Harness h(Options(1.0));
  h.Step();
  ASSERT_EQ(h.phase(), ExperimentPhase::kSettling);
  h.pool.Skip(3 * kTs);
  h.Step();
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kSampleGap);
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);
}

TEST(ReachControllerBadPolls, TimeGoingBackAborts) {
  Harness h = Exciting();
  ReachReadings r = h.pool.Poll();
  r.time_s -= 5.0;
  h.Step(r);
  EXPECT_EQ(h.phase(), ExperimentPhase::kAborted);
  EXPECT_EQ(h.reason(), AbortReason::kSampleGap);
  EXPECT_LT(h.controller.pipeline().experiment_state().sample_gap_s, 0.0);
  EXPECT_TRUE(h.writes.back().restore);
}

// ----- restart after an interrupted experiment --------------------------------------------------

RestartContext Context(std::optional<double> configured = std::nullopt) {
  RestartContext c;
  c.reach = "pool1";
  c.actuator = "gate1_setpoint";
  c.setpoint_min = kSetpointMin;
  c.setpoint_max = kSetpointMax;
  c.configured_nominal = configured;
  return c;
}

GuardReading Guard(double nominal) {
  GuardReading g;
  g.kind = GuardReading::Kind::kFound;
  g.guard.reach = "pool1";
  g.guard.actuator = "gate1_setpoint";
  g.guard.experiment = "pool1-prbs";
  g.guard.nominal_setpoint = nominal;
  g.guard.started_utime_us = 1700000000000000;
  return g;
}

TEST(ReachControllerRestart, AGuardFromACrashRestoresItsNominalNotTheExcitedReading) {
  // The crash left the actuator at a PRBS level, 1.2 + 0.1.
  Harness h(Options(std::nullopt), /*actuator=*/1.3);
  const RestartDecision decision = DecideRestart(Context(), Guard(1.2));
  ASSERT_EQ(decision.action, RestartDecision::Action::kRestore);
  EXPECT_EQ(h.controller.ApplyRestart(decision), "");
  EXPECT_EQ(h.controller.nominal(), 1.2);
  ASSERT_TRUE(h.controller.pipeline().experiment_plan());
  EXPECT_EQ(h.controller.pipeline().experiment_plan()->prbs.nominal, 1.2);
  EXPECT_FALSE(h.controller.excitation_allowed());

  // Polls before the PLC confirms the restore: each asks for the guard's nominal again, the
  // excited reading is not the nominal, and nothing starts.
  ASSERT_TRUE(decision.restore_setpoint);
  EXPECT_EQ(*decision.restore_setpoint, 1.2);
  h.confirm_writes = false;
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(h.Step().nominal_read);
  EXPECT_EQ(h.controller.nominal(), 1.2);
  EXPECT_TRUE(h.started_at.empty());
  ASSERT_EQ(h.writes.size(), 3U);
  for (const Write& w : h.writes) {
    EXPECT_EQ(w.value, 1.2) << "poll " << w.poll;
    EXPECT_TRUE(w.restore) << "poll " << w.poll;
  }

  // The PLC confirms it: the guard has done its job, experiments may start.
  const ReachWriteOutcome confirmed = h.controller.OnWriteResult({true, 1.2, h.write_id});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_TRUE(confirmed.remove_guard);
  EXPECT_TRUE(h.controller.excitation_allowed());
  EXPECT_FALSE(h.controller.restore_pending());

  // The on_start experiment now runs around the guarded nominal and ends on it.
  h.confirm_writes = true;
  h.writes.clear();
  const int start = h.polls;
  h.Steps(static_cast<int>(kSettle + kExcite) + 1);
  EXPECT_EQ(h.started_at, std::vector<int>{start});
  ASSERT_EQ(h.writes.size(), static_cast<std::size_t>(kExcite + 2));
  EXPECT_EQ(h.writes.front().value, 1.2);
  for (std::int64_t k = 0; k < kExcite; ++k)
    EXPECT_NEAR(h.writes[static_cast<std::size_t>(k + 1)].value, Prbs(1.2, k), 1e-12);
  EXPECT_EQ(h.writes.back().value, 1.2);
  EXPECT_TRUE(h.writes.back().restore);
  ExpectInsideLimits(h.writes);
}

TEST(ReachControllerRestart, AnAbortAfterARestartRestoresTheGuardedNominal) {
  Harness h(Options(std::nullopt), /*actuator=*/1.1);
  EXPECT_EQ(h.controller.ApplyRestart(DecideRestart(Context(), Guard(1.2))), "");
  // The first poll writes the guard's nominal (confirmed at once here), then starts.
  h.Steps(static_cast<int>(kSettle) + 4);
  EXPECT_EQ(h.writes.front().value, 1.2);
  EXPECT_TRUE(h.writes.front().restore);
  EXPECT_EQ(h.started_at, std::vector<int>{0});
  ASSERT_EQ(h.phase(), ExperimentPhase::kExciting);
  ReachReadings down;
  down.link_ok = false;
  down.status_ok = false;
  down.time_s = h.pool.Poll().time_s;
  h.Step(down);
  EXPECT_EQ(h.reason(), AbortReason::kLinkLost);
  EXPECT_EQ(h.writes.back().value, 1.2);
  EXPECT_TRUE(h.writes.back().restore);
}

TEST(ReachControllerRestart, TheConfiguredNominalWinsForTheNextExperiment) {
  Harness h(Options(1.0), /*actuator=*/1.3);
  const RestartDecision decision = DecideRestart(Context(1.0), Guard(1.2));
  EXPECT_EQ(decision.restore_setpoint, 1.2);
  EXPECT_EQ(h.controller.ApplyRestart(decision), "");
  EXPECT_EQ(h.controller.nominal(), 1.0);
  EXPECT_EQ(h.controller.pipeline().experiment_plan()->prbs.nominal, 1.0);
  // The guard's nominal is restored first, and nothing starts before the PLC confirms it.
  h.confirm_writes = false;
  EXPECT_FALSE(h.Step().nominal_read);
  ASSERT_EQ(h.writes.size(), 1U);
  EXPECT_EQ(h.writes[0].value, 1.2);
  EXPECT_TRUE(h.writes[0].restore);
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.controller.OnWriteResult({true, 1.2, h.write_id}).restore_confirmed);
  // Then the experiment settles at the configured nominal.
  h.confirm_writes = true;
  h.Step();
  EXPECT_EQ(h.started_at, std::vector<int>{1});
  EXPECT_EQ(h.writes.back().value, 1.0);
  EXPECT_TRUE(h.writes.back().restore);  // settling holds the nominal (experiment.h)
}

TEST(ReachControllerRestart, ARefusalWithoutANominalNeverExcitesNorReadsOne) {
  Harness h(Options(std::nullopt), /*actuator=*/1.3);
  GuardReading corrupt;
  corrupt.kind = GuardReading::Kind::kCorrupt;
  corrupt.problem = "state/pool1.experiment.json: not JSON";
  EXPECT_EQ(h.controller.ApplyRestart(DecideRestart(Context(), corrupt)), "");
  // Nothing is pending: a write of the reading confirms nothing, and it stays refused.
  EXPECT_FALSE(h.controller.restore_pending());
  EXPECT_FALSE(h.controller.OnWriteResult({true, 1.3, h.write_id}).restore_confirmed);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(h.Step().nominal_read);
  EXPECT_FALSE(h.controller.nominal_known());
  EXPECT_FALSE(h.controller.excitation_allowed());
  EXPECT_TRUE(h.started_at.empty());
  EXPECT_TRUE(h.writes.empty());
}

TEST(ReachControllerRestart, NoGuardStartsAsUsual) {
  Harness h(Options(std::nullopt), /*actuator=*/1.0);
  EXPECT_EQ(h.controller.ApplyRestart(DecideRestart(Context(), GuardReading{})), "");
  EXPECT_TRUE(h.controller.excitation_allowed());
  const ReachPollOutcome first = h.Step();
  ASSERT_TRUE(first.nominal_read);
  EXPECT_EQ(*first.nominal_read, 1.0);
  EXPECT_EQ(h.started_at, std::vector<int>{0});
}

// ----- determinism ------------------------------------------------------------------------------

bool Same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

struct Trace {
  std::vector<Write> writes;
  std::vector<int> started_at;
  std::vector<bool> online_updated;
  std::vector<IntegratorDelaySnapshot> snapshots;
  std::vector<ExperimentPhase> phases;
  AbortReason reason = AbortReason::kNone;
  double nominal = 0.0;
};

// Nominal read from the PLC, a start, tolerated failed polls, a missed poll, then a gap abort.
Trace RunScript() {
  Harness h(Options(std::nullopt), 0.95);
  Trace t;
  auto step = [&](const ReachReadings& r) {
    const ReachPollOutcome outcome = h.Step(r);
    t.online_updated.push_back(outcome.actions.online_updated);
    t.phases.push_back(h.phase());
    if (h.controller.pipeline().online_id() != nullptr)
      t.snapshots.push_back(h.controller.pipeline().online_id()->Snapshot());
  };
  for (int i = 0; i < 10; ++i) step(h.pool.Poll());
  step(LevelBlockFailed(h.pool.Poll()));
  step(LevelBlockFailed(h.pool.Poll()));
  for (int i = 0; i < 6; ++i) step(h.pool.Poll());
  h.pool.Skip(kTs);
  step(h.pool.Poll());
  h.pool.Skip(4 * kTs);
  for (int i = 0; i < 4; ++i) step(h.pool.Poll());
  t.writes = h.writes;
  t.started_at = h.started_at;
  t.reason = h.reason();
  t.nominal = h.controller.nominal();
  return t;
}

TEST(ReachControllerDeterminism, TheSameReadingsGiveTheSameActionsTwice) {
  const Trace a = RunScript();
  const Trace b = RunScript();
  EXPECT_EQ(a.reason, AbortReason::kSampleGap);  // the script did reach its end
  EXPECT_EQ(a.nominal, 0.95);
  EXPECT_EQ(a.started_at, b.started_at);
  EXPECT_EQ(a.phases, b.phases);
  EXPECT_EQ(a.online_updated, b.online_updated);
  EXPECT_EQ(a.reason, b.reason);
  EXPECT_EQ(a.nominal, b.nominal);
  ASSERT_EQ(a.writes.size(), b.writes.size());
  for (std::size_t i = 0; i < a.writes.size(); ++i) {
    EXPECT_EQ(a.writes[i].poll, b.writes[i].poll) << i;
    EXPECT_EQ(a.writes[i].value, b.writes[i].value) << i;  // bit for bit
    EXPECT_EQ(a.writes[i].restore, b.writes[i].restore) << i;
    EXPECT_EQ(a.writes[i].record_complete, b.writes[i].record_complete) << i;
  }
  ASSERT_EQ(a.snapshots.size(), b.snapshots.size());
  ASSERT_FALSE(a.snapshots.empty());
  for (std::size_t i = 0; i < a.snapshots.size(); ++i) {
    const IntegratorDelaySnapshot& x = a.snapshots[i];
    const IntegratorDelaySnapshot& y = b.snapshots[i];
    EXPECT_EQ(x.valid, y.valid) << i;
    EXPECT_EQ(x.sample, y.sample) << i;
    EXPECT_EQ(x.delay_samples, y.delay_samples) << i;
    EXPECT_TRUE(Same(x.b, y.b)) << i;
    EXPECT_TRUE(Same(x.c_m, y.c_m)) << i;
    EXPECT_TRUE(Same(x.d_m, y.d_m)) << i;
    EXPECT_TRUE(Same(x.loss, y.loss)) << i;
    EXPECT_EQ(x.flags, y.flags) << i;
  }
}

}  // namespace
}  // namespace canalid::core
