// LevelPid against closed forms of sampled loops around an integrating pool: S dy/dt = u - d,
// whose zero-order-hold discretisation y_{k+1} = y_k + Ts (u_k - d) / S is exact for a flow held
// over the sample.  The loop in each test is simulated here, not by sim/.
#include "sim/level_pid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalid::sim {
namespace {

LevelPidConfig Config(double kp, double ki, double kd, double ts) {
  LevelPidConfig c;
  c.setpoint_m = 1.0;
  c.kp = kp;
  c.ki = ki;
  c.kd = kd;
  c.min_flow_m3s = 0.0;
  c.max_flow_m3s = 100.0;
  c.sample_time_s = ts;
  return c;
}

TEST(LevelPid, ProportionalOnIntegratorDecaysGeometrically) {
  // P only, disturbance d equal to the starting flow: e_{k+1} = (1 - Ts kp / S) e_k exactly.
  const double area = 2.0, ts = 0.1, kp = 5.0, d = 3.0;
  LevelPid pid(Config(kp, 0.0, 0.0, ts));
  double y = 0.8;
  pid.Reset(d, y);
  const double ratio = 1.0 - ts * kp / area;
  for (int k = 0; k < 40; ++k) {
    EXPECT_NEAR(1.0 - y, 0.2 * std::pow(ratio, k), 1e-12) << k;
    y += ts * (pid.Update(y) - d) / area;
  }
}

TEST(LevelPid, PiRejectsAnOutflowStepAsTheContinuousClosedForm) {
  // S = 1, kp = 2 w, ki = w^2: Y/D = -s / (s + w)^2, so a step d of the outflow gives
  // y(t) - r = -d t e^(-w t) (peak d / (e w) at t = 1 / w) and no steady-state error.  With
  // Ts = 1 ms the sampled loop differs from it by O(w Ts) = 0.1 % of the peak; 1 % is allowed.
  const double w = 1.0, ts = 1e-3, d = 0.5, u0 = 2.0;
  LevelPid pid(Config(2.0 * w, w * w, 0.0, ts));
  double y = 1.0;
  pid.Reset(u0, y);
  const double peak = d / (std::exp(1.0) * w);
  double worst = 0.0;
  for (int k = 0; k <= 15000; ++k) {
    const double t = k * ts;
    worst = std::max(worst, std::abs((y - 1.0) - (-d * t * std::exp(-w * t))));
    y += ts * (pid.Update(y) - (u0 + d)) / 1.0;
  }
  EXPECT_LT(worst, 0.01 * peak);
  EXPECT_NEAR(y, 1.0, 1e-5);                    // e^-15 * 15 * d of the closed form
  EXPECT_NEAR(pid.output_m3s(), u0 + d, 1e-4);  // the pump ends up passing the new outflow
}

TEST(LevelPid, AntiWindupKeepsTheFlowInItsLimitsAndAvoidsOvershoot) {
  // A setpoint 1 m above the level with the pump limited to 1.5 m3/s against an outflow of
  // 1 m3/s on S = 1: the level can only rise at 0.5 m/s, so for about 2 s the error stays large.
  // A PI that kept integrating would then carry ki * integral(e) ~ 1 m3/s of windup and overshoot
  // by tens of centimetres (computed below with the same gains); conditional integration
  // must keep the overshoot under 2 % of the step.
  const double ts = 0.01, kp = 4.0, ki = 4.0, d = 1.0;
  LevelPidConfig c = Config(kp, ki, 0.0, ts);
  c.max_flow_m3s = 1.5;
  c.setpoint_m = 1.0;
  LevelPid pid(c);
  double y = 0.0;
  pid.Reset(d, y);
  double naive_y = 0.0, naive_i = d, max_y = 0.0, max_naive = 0.0;
  for (int k = 0; k < 3000; ++k) {
    const double u = pid.Update(y);
    ASSERT_GE(u, c.min_flow_m3s);
    ASSERT_LE(u, c.max_flow_m3s);
    y += ts * (u - d);
    max_y = std::max(max_y, y);
    const double e = 1.0 - naive_y;
    naive_i += ki * ts * e;
    naive_y += ts * (std::clamp(kp * e + naive_i, 0.0, 1.5) - d);
    max_naive = std::max(max_naive, naive_y);
  }
  EXPECT_LT(max_y - 1.0, 0.02);
  EXPECT_GT(max_naive - 1.0, 0.2);  // the test can tell windup from none
  EXPECT_NEAR(y, 1.0, 1e-6);
}

TEST(LevelPid, ReverseActionPumpsMoreWhenTheLevelIsHigh) {
  LevelPidConfig c = Config(2.0, 0.0, 0.0, 1.0);
  c.direct_action = false;
  LevelPid pid(c);
  pid.Reset(1.0, 1.0);
  EXPECT_DOUBLE_EQ(pid.Update(1.25), 1.0 + 2.0 * 0.25);
  EXPECT_DOUBLE_EQ(pid.Update(0.75), 1.0 - 2.0 * 0.25);
}

TEST(LevelPid, DerivativeActsOnTheMeasurementOnly) {
  // kd alone: a level rising 0.01 m per 0.5 s sample gives u0 - kd * 0.02 m/s; a setpoint jump
  // with a still level gives no kick.
  LevelPid pid(Config(0.0, 0.0, 3.0, 0.5));
  pid.Reset(1.0, 1.0);
  EXPECT_NEAR(pid.Update(1.01), 1.0 - 3.0 * 0.02, 1e-12);
  EXPECT_NEAR(pid.Update(1.02), 1.0 - 3.0 * 0.02, 1e-12);
  pid.SetSetpoint(5.0);
  EXPECT_NEAR(pid.Update(1.02), 1.0, 1e-12);
}

TEST(LevelPid, StartsBumplessAndRejectsBadConfigurations) {
  LevelPid pid(Config(1.0, 1.0, 1.0, 0.1));
  pid.Reset(7.0, 1.0);
  EXPECT_DOUBLE_EQ(pid.Update(1.0), 7.0);
  LevelPidConfig bad = Config(1.0, 1.0, 0.0, 0.1);
  bad.kp = -1.0;
  EXPECT_THROW(LevelPid{bad}, std::invalid_argument);
  bad = Config(1.0, 1.0, 0.0, 0.0);
  EXPECT_THROW(LevelPid{bad}, std::invalid_argument);
  bad = Config(1.0, 1.0, 0.0, 0.1);
  bad.min_flow_m3s = 2.0;
  bad.max_flow_m3s = 1.0;
  EXPECT_THROW(LevelPid{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace canalid::sim
