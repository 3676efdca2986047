#pragma once
// Fully populated instances of every canalid LCM type, and field-by-field comparisons, shared by
// the LCM suites.
#include <gtest/gtest.h>

#include <canalid/command_t.hpp>
#include <canalid/config_t.hpp>
#include <canalid/experiment_state_t.hpp>
#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include <cmath>

namespace canalid::testing {

inline canalid::sample_t MakeSample(int64_t sequence) {
  canalid::sample_t m;
  m.utime = 1763700000000000 + sequence * 1000;
  m.sequence = sequence;
  m.source = "plc.pool2";
  m.reach = "pool2";
  m.status = canalid::sample_t::STATUS_EXCEPTION;
  m.exception_code = 2;
  m.round_trip_s = 4.5e-5f;
  m.num_channels = 3;
  m.channel_names = {"level_m", "flow_m3s", "gate_m"};
  m.values = {1.234, -0.5, 0.25 * static_cast<double>(sequence)};
  m.quality = {canalid::sample_t::QUALITY_VALID, canalid::sample_t::QUALITY_OUT_OF_RANGE,
               canalid::sample_t::QUALITY_READ_FAILED};
  return m;
}

inline void ExpectEqual(const canalid::sample_t& a, const canalid::sample_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.reach, b.reach);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.exception_code, b.exception_code);
  EXPECT_EQ(a.round_trip_s, b.round_trip_s);
  EXPECT_EQ(a.channel_names, b.channel_names);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.quality, b.quality);
}

inline canalid::model_snapshot_t MakeModel() {
  canalid::model_snapshot_t m;
  m.utime = 1763700000123456;
  m.reach = "pool2";
  m.model_kind = "id";
  m.estimator = "rls-directional";
  m.samples_used = 86400;
  m.num_params = 2;
  m.param_names = {"delay_s", "area_m2"};
  m.param_values = {540.0, 6000.0};
  m.param_std_devs = {12.5, NAN};
  m.trace_p = 1e-3;
  m.condition_number = 2.5e4;
  m.excitation = 0.02;
  m.prediction_error_rms = 0.004;
  // lcm-gen constants are unnamed enums: C++20 deprecates | between them without a cast.
  m.flags = static_cast<int32_t>(canalid::model_snapshot_t::FLAG_LOW_EXCITATION) |
            static_cast<int32_t>(canalid::model_snapshot_t::FLAG_FROZEN);
  return m;
}

inline void ExpectEqual(const canalid::model_snapshot_t& a, const canalid::model_snapshot_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.reach, b.reach);
  EXPECT_EQ(a.model_kind, b.model_kind);
  EXPECT_EQ(a.estimator, b.estimator);
  EXPECT_EQ(a.samples_used, b.samples_used);
  EXPECT_EQ(a.param_names, b.param_names);
  EXPECT_EQ(a.param_values, b.param_values);
  ASSERT_EQ(a.param_std_devs.size(), b.param_std_devs.size());
  EXPECT_EQ(a.param_std_devs[0], b.param_std_devs[0]);
  EXPECT_TRUE(std::isnan(b.param_std_devs[1]));
  EXPECT_EQ(a.trace_p, b.trace_p);
  EXPECT_EQ(a.condition_number, b.condition_number);
  EXPECT_EQ(a.excitation, b.excitation);
  EXPECT_EQ(a.prediction_error_rms, b.prediction_error_rms);
  EXPECT_EQ(a.flags, b.flags);
}

inline canalid::experiment_state_t MakeExperiment() {
  canalid::experiment_state_t m;
  m.utime = 1763700000200000;
  m.reach = "pool2";
  m.experiment = "pool2_prbs";
  m.state = canalid::experiment_state_t::STATE_EXCITING;
  m.step = 17;
  m.num_steps = 63;
  m.setpoint_channel = "pool2.gate_m";
  m.setpoint = 0.42;
  m.reason = "operator";
  return m;
}

inline void ExpectEqual(const canalid::experiment_state_t& a,
                        const canalid::experiment_state_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.reach, b.reach);
  EXPECT_EQ(a.experiment, b.experiment);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.step, b.step);
  EXPECT_EQ(a.num_steps, b.num_steps);
  EXPECT_EQ(a.setpoint_channel, b.setpoint_channel);
  EXPECT_EQ(a.setpoint, b.setpoint);
  EXPECT_EQ(a.reason, b.reason);
}

inline canalid::health_t MakeHealth() {
  canalid::health_t m;
  m.utime = 1763700000300000;
  m.component = "plc.pool2";
  m.uptime_s = 3600.5;
  m.num_counters = 2;
  m.counter_names = {"polls", "read_errors.timeout"};
  m.counter_values = {3600, 3};
  m.num_gauges = 1;
  m.gauge_names = {"last_round_trip_s"};
  m.gauge_values = {4.2e-5};
  return m;
}

inline void ExpectEqual(const canalid::health_t& a, const canalid::health_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.component, b.component);
  EXPECT_EQ(a.uptime_s, b.uptime_s);
  EXPECT_EQ(a.counter_names, b.counter_names);
  EXPECT_EQ(a.counter_values, b.counter_values);
  EXPECT_EQ(a.gauge_names, b.gauge_names);
  EXPECT_EQ(a.gauge_values, b.gauge_values);
}

inline canalid::config_t MakeConfig() {
  canalid::config_t m;
  m.utime = 1763700000000001;
  m.path = "/etc/canalid/canalid.toml";
  m.version = "0.1.0";
  m.text = "[daemon]\nperiod_s = 1.0\n# a line with \"quotes\" and unicode: \xc2\xb5s\n";
  return m;
}

inline void ExpectEqual(const canalid::config_t& a, const canalid::config_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.text, b.text);
}

inline canalid::command_t MakeCommand() {
  canalid::command_t m;
  m.utime = 1763700000400000;
  m.counter = 42;
  m.sender = "operator-console";
  m.kind = canalid::command_t::KIND_START_EXPERIMENT;
  m.reach = "pool2";
  m.argument = "prbs-63";
  m.hmac_size = 32;
  m.hmac.resize(32);
  for (int i = 0; i < 32; ++i)
    m.hmac[static_cast<std::size_t>(i)] = static_cast<uint8_t>(255 - 7 * i);
  return m;
}

inline void ExpectEqual(const canalid::command_t& a, const canalid::command_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.counter, b.counter);
  EXPECT_EQ(a.sender, b.sender);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.reach, b.reach);
  EXPECT_EQ(a.argument, b.argument);
  EXPECT_EQ(a.hmac, b.hmac);
}

}  // namespace canalid::testing
