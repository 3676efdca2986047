// The two lab canals of config/sim: the flume paper's flume (upstream level held by the pump's PID)
// and the LPV paper's two-pool pump pilot.  Truths: the papers' nominal settings, mass
// conservation, the closed-form storage slope dQ / (L b) of a pumped pool and its wave travel time
// L / (c + V).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/canal_config.h"
#include "sim/saint_venant.h"
#include "sim/scenario.h"

namespace canalid::sim {
namespace {

Canal Load(const std::string& name) {
  return LoadCanal(std::string(CANALID_SOURCE_DIR) + "/config/sim/" + name);
}

TEST(LabFlume, LoadsAtThePapersNominalRegime) {
  const Canal canal = Load("lab-flume.toml");
  ASSERT_EQ(canal.pools.size(), 2u);
  ASSERT_EQ(canal.level_controls.size(), 1u);
  SaintVenantCanal plant(canal);
  // The flume paper's nominal regime: gate 15 mm, highest crest 33 mm (0.1 mm: the flow 0.30 L/s
  // and Cw 1.7 were chosen to give them to a tenth of a millimetre).
  EXPECT_NEAR(plant.structure_setting(0), 0.015, 1e-4);
  EXPECT_NEAR(plant.structure_setting(1), 0.033, 1e-4);
  EXPECT_DOUBLE_EQ(plant.ControlledLevel(0), 0.070);
  // Without events it stays still, the PID included (it starts bumpless at the steady flow).
  for (int k = 0; k < 1200; ++k) plant.Step(0.05);
  EXPECT_NEAR(plant.DownstreamDepth(0), 0.070, 1e-7);
  EXPECT_NEAR(plant.DownstreamDepth(1), 0.050, 1e-7);
  EXPECT_NEAR(plant.PoolInflow(0), 0.0003, 1e-9);
}

TEST(LabFlume, PumpPidHoldsTheUpstreamLevelThroughAGateStep) {
  SaintVenantCanal plant(Load("lab-flume.toml"));
  // The flume paper's experiment: the gate from 15 to 20 mm, then 360 s at dt = 0.05 s.
  plant.SetStructureSetting(0, 0.020);
  double worst = 0.0, late_worst = 0.0, late_sum = 0.0;
  int late_n = 0;
  for (int k = 1; k <= 7200; ++k) {
    plant.Step(0.05);
    const double dev = plant.ControlledLevel(0) - 0.070;
    worst = std::max(worst, std::abs(dev));
    if (k * 0.05 > 45.0) late_worst = std::max(late_worst, std::abs(dev));
    if (k * 0.05 > 300.0) {
      late_sum += dev;
      ++late_n;
    }
    ASSERT_GE(plant.PoolInflow(0), 0.0);
    ASSERT_LE(plant.PoolInflow(0), 0.0025 + 1e-12);
  }
  // The gate step draws the reservoir down by a few millimetres (the paper's "fast transients
  // that are quickly removed", measured 3.1 mm); 45 s later only the main pool's waves, which
  // the gate passes back, move it (measured 0.07 mm), and the PI leaves no mean error.
  EXPECT_GT(worst, 1e-3);  // the step does disturb it
  EXPECT_LT(worst, 5e-3);
  EXPECT_LT(late_worst, 2e-4);
  EXPECT_LT(std::abs(late_sum / late_n), 2e-5);
  // At the new steady state the pump passes what leaves over the crest (waves: 1 %).
  EXPECT_NEAR(plant.PoolInflow(0), plant.StructureFlow(1), 0.01 * plant.StructureFlow(1));
  EXPECT_GT(plant.PoolInflow(0), 0.0003);
  // Mass balance: the issue asks for under 0.1 % over a day.
  EXPECT_LT(plant.mass_balance().relative_error, 1e-4);
}

TEST(LabFlume, EventsOnThePidsPumpAreOverridden) {
  SaintVenantCanal plant(Load("lab-flume.toml"));
  plant.SetUpstream(0.002);
  plant.Step(0.05);
  EXPECT_NEAR(plant.PoolInflow(0), 0.0003, 1e-9);
}

TEST(LabFlume, ActuatorMustBeAPump) {
  Canal canal = Load("lab-flume.toml");
  canal.level_controls[0].actuator_pool = "1";  // an undershot gate
  EXPECT_THROW(SaintVenantCanal{canal}, std::invalid_argument);
  canal.level_controls[0].actuator_pool.clear();
  canal.level_controls[0].level_pool = "9";
  EXPECT_THROW(SaintVenantCanal{canal}, std::invalid_argument);
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CANALID_BINARY_DIR) / "tests" / ("lab_canals_" + name);
  std::ofstream(path) << text;
  return path.string();
}

TEST(LabFlume, ScenarioEventsOnThePidsPumpAndBadLoopKeysAreConfigErrors) {
  const Canal canal = Load("lab-flume.toml");
  const std::string scenario = WriteTemp("pump-event.toml", R"(duration_s = 1.0
output_period_s = 0.15
[[event]]
time_s = 0.0
target = "inflow"
kind = "set"
value = 0.001
[output]
y = "pool2.level_downstream"
)");
  try {
    LoadScenario(scenario, canal);
    FAIL() << "an event on the PID's pump must be refused";
  } catch (const ConfigError& e) {
    ASSERT_EQ(e.problems().size(), 1u);
    EXPECT_NE(e.problems()[0].find("level control pump"), std::string::npos) << e.problems()[0];
  }
  // Simulating only the main pool drops the loop (its pump is not simulated), and the inflow is
  // then free for events.
  const std::string main_only = WriteTemp("main-only.toml", R"(duration_s = 1.0
output_period_s = 0.15
first_pool = "2"
[[event]]
time_s = 0.0
target = "inflow"
kind = "set"
value = 0.0004
[output]
y = "pool2.level_downstream"
)");
  EXPECT_TRUE(LoadScenario(main_only, canal).canal.level_controls.empty());

  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/config/sim/lab-flume.toml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string bad = WriteTemp(
      "bad-loop.toml", text +
                           "\n[[level_control]]\nlevel = \"pool2.depth\"\npump = \"pool2.gate\"\n"
                           "setpoint_m = 0.05\nmax_flow_m3s = 0.001\nsample_time_s = 0.15\n"
                           "kq = 1.0\n");
  try {
    LoadCanal(bad);
    FAIL() << "a bad level control must be refused";
  } catch (const ConfigError& e) {
    // The unknown key, the level and the pump, each with its line.
    EXPECT_EQ(e.problems().size(), 3u);
  }
}

struct Record {
  std::vector<double> t, y1, y2;
};

// Steps pump `pump` (-1: B1, the inflow; 0: B2) by dq at t = 10 s and records 300 s.
Record PilotStep(int pump, double dq) {
  SaintVenantCanal plant(Load("pump-pilot.toml"));
  Record r;
  const double dt = 0.125;
  for (int k = 1; k <= 2400; ++k) {
    if (k == 80) {
      if (pump < 0) {
        plant.SetUpstream(plant.upstream() + dq);
      } else {
        plant.SetStructureSetting(pump, plant.structure_setting(pump) + dq);
      }
    }
    plant.Step(dt);
    r.t.push_back(k * dt);
    r.y1.push_back(plant.DownstreamDepth(0));
    r.y2.push_back(plant.DownstreamDepth(1));
  }
  // The scheme weights the boundary flow change by theta = 0.6 where the accounting uses the
  // trapezoid, which leaves (theta - 1/2) dt dq = 1.25e-6 m3 for the B1 step (1.4e-5 of the
  // inflow); the issue's target is 1e-3.
  EXPECT_LT(plant.mass_balance().relative_error, 1e-4);
  return r;
}

// Least-squares slope of y over t in [t0, t1].
double Slope(const std::vector<double>& t, const std::vector<double>& y, double t0, double t1) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t0 || t[i] > t1) continue;
    n += 1;
    st += t[i];
    sy += y[i];
    stt += t[i] * t[i];
    sty += t[i] * y[i];
  }
  return (n * sty - st * sy) / (n * stt - st * st);
}

// First time from `from` (the step, taking effect at the step ending then) at which y departs
// from its value before by more than 1 % of `scale`.
double Arrival(const Record& r, const std::vector<double>& y, double from, double scale) {
  double base = 0.0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < from - 1e-9) base = y[i];
    if (r.t[i] > from - 1e-9 && std::abs(y[i] - base) > 0.01 * scale) return r.t[i];
  }
  return -1.0;
}

TEST(PumpPilot, StartsStillAndB2StepDrainsP1AndFillsP2AfterTheWaveTravelTime) {
  const double dq = 5e-5, length = 12.0, width = 0.15, depth = 0.20;
  // Closed forms: each pool is a tank of 1.8 m2 between pumps, so the levels ramp at
  // dq / (L b); the front crosses the pool at c + V with c = sqrt(g y).
  const double ramp = dq / (length * width);
  const double travel = length / (std::sqrt(9.81 * depth) + 0.0002 / (width * depth));
  const Record r = PilotStep(0, dq);
  // Still before the step (bumpless steady start).
  EXPECT_NEAR(r.y1[70], depth, 1e-9);
  EXPECT_NEAR(r.y2[70], depth, 1e-9);
  // y1 is at B2: it falls at once; y2 is 12 m away: it waits for the wave.  The front is
  // detected at 1 % of the half-round-trip rise dq / (b c), within 15 % of L / (c + V) (the
  // scheme spreads a front over a few cells).
  const double rise = dq / (width * std::sqrt(9.81 * depth));
  EXPECT_LE(Arrival(r, r.y1, 10.0, rise), 10.0 + 1e-9);
  const double arrival = Arrival(r, r.y2, 10.0, rise) - 10.0;
  EXPECT_NEAR(arrival, travel, 0.15 * travel);
  // The LPV paper identifies delays of 5 to 17 samples of 0.5 s (Table 3, 4): 2.5 to 8.5 s.
  EXPECT_LE(arrival, 8.5 + 0.5);
  // Integrators: the late slopes are -+ dq / (L b).  The waves bounce between the pumps (both
  // reflect), so the levels climb in stairs of one round trip 2 L / c = 17 s; a least-squares
  // slope over 250 s (15 stairs) is within 3 % of the mean ramp.
  EXPECT_NEAR(Slope(r.t, r.y1, 50.0, 300.0), -ramp, 0.03 * ramp);
  EXPECT_NEAR(Slope(r.t, r.y2, 50.0, 300.0), ramp, 0.03 * ramp);
}

TEST(PumpPilot, B1StepRaisesOnlyP1AsTheDecoupledModelSays) {
  // The LPV paper models the pools uncoupled (P12 = P21 = 0): with B2 holding its flow, P2 never
  // sees a B1 step.
  const double dq = 1e-4;
  const Record r = PilotStep(-1, dq);
  const double ramp = dq / (12.0 * 0.15);
  EXPECT_NEAR(Slope(r.t, r.y1, 50.0, 300.0), ramp, 0.03 * ramp);
  for (double y : r.y2) ASSERT_NEAR(y, 0.20, 1e-12);
  const double arrival = Arrival(r, r.y1, 10.0, dq / (0.15 * 1.4)) - 10.0;
  EXPECT_GT(arrival, 0.85 * 12.0 / 1.41);
}

}  // namespace
}  // namespace canalid::sim
