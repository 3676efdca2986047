// config/canalidd-asce2.toml against the real `canalsim serve` of ASCE canal 2: the channels the
// config maps onto a PlcPoller read pool 2 where docs/register-map.md says they are.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>

#include "daemon/canalidd/driver_config.h"
#include "daemon/config/config_loader.h"
#include "daemon/config/plan_from_config.h"
#include "tests/sim/serve_process.h"

namespace canalid::daemon {
namespace {

TEST(Asce2CanalsimTest, PollerReadsPoolTwoAtItsSteadyState) {
  const config::DaemonConfig config =
      LoadDaemonConfig(std::string(CANALID_SOURCE_DIR) + "/config/canalidd-asce2.toml");
  const std::filesystem::path log =
      std::filesystem::path(CANALID_BINARY_DIR) / "asce2_canalsim_test.stderr";
  // Lockstep: the plant does not move, so the readings are the initial steady state.
  testing::ServeProcess server(
      {"--canal", testing::SourcePath("config/sim/asce-canal2.toml"), "--plc",
       testing::SourcePath("config/sim/plc/asce2.toml"), "--lockstep"},
      log);
  auto link = std::get<drivers::ModbusTcpConfig>(BuildModbusConfig(config.plcs[0]));
  link.port = server.port();  // the config's 1502 is the demo's; the test takes a free port

  std::mutex mutex;
  std::condition_variable ready;
  bool notified = false;
  drivers::PlcPoller poller(BuildPollerConfig(config, config.plcs[0]),
                            std::make_unique<drivers::ModbusPort>(link), [&] {
                              std::lock_guard lock(mutex);
                              notified = true;
                              ready.notify_one();
                            });
  poller.Start();
  drivers::PollSample sample;
  bool got = false;
  {
    std::unique_lock lock(mutex);
    // Bounded wait for the first poll (a few ms on loopback).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!got) {
      ASSERT_TRUE(ready.wait_until(lock, deadline, [&] { return notified; })) << "no sample";
      notified = false;
      lock.unlock();
      poller.DrainSamples([&](const drivers::PollSample& s) {
        if (!got && s.status.ok()) {
          sample = s;
          got = true;
        }
      });
      lock.lock();
    }
  }
  poller.Stop();

  ASSERT_EQ(sample.values.size(), 6u);
  for (std::size_t i = 0; i < sample.values.size(); ++i) {
    EXPECT_TRUE(sample.valid(i)) << poller.config().channels[i].name;
  }
  // asce-canal2.toml: 11 m3/s enter pool 1, whose offtake takes 1, so 10 m3/s pass gate 1 into
  // pool 2; pool 2's offtake is at its downstream end, so its outflow (structure + offtake) is
  // also 10; target depth 2.1 m. Tolerance 1e-3: the steady state is solved iteratively and
  // served as float32.
  EXPECT_NEAR(sample.values[1], 10.0, 1e-3);  // pool2_inflow
  EXPECT_NEAR(sample.values[2], 10.0, 1e-3);  // pool2_outflow
  EXPECT_NEAR(sample.values[3], 2.1, 1e-3);   // pool2_level
  // The gate's actual opening equals its setpoint at steady state, inside the actuator range.
  EXPECT_EQ(sample.values[4], sample.values[5]);
  EXPECT_GT(sample.values[5], 0.05);
  EXPECT_LT(sample.values[5], 2.0);

  // The designed experiment fits around that opening: 7.5 % either way stays in [0.05, 2].
  const core::ExperimentPlan plan =
      config::BuildExperimentPlan(config, config.experiments[0], sample.values[5]);
  EXPECT_DOUBLE_EQ(plan.prbs.amplitude, 0.075 * sample.values[5]);
}

}  // namespace
}  // namespace canalid::daemon
