// Integration tests of `canalsim serve`: the real program on a free loopback port, driven by
// libmodbus, mbpoll and pymodbus masters, mostly in lockstep mode so that plant time advances
// only when a test says so.  Expected numbers come from the register map (docs/register-map.md,
// 0-based addresses written out here on purpose), the canal file (target depths, flows) and the
// PLC file config/sim/plc/asce2.toml (rate 0.005 m/s, 10 s steps, 300 s heartbeat timeout).
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "tests/sim/serve_process.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

// System registers.
constexpr int kIrStatus = 0;
constexpr int kIrFaults = 1;
constexpr int kIrTimeFloat = 2;
constexpr int kIrTimeSeconds = 4;
constexpr int kIrStepCount = 6;
constexpr int kIrPoolCount = 7;
constexpr int kHrHeartbeat = 0;
constexpr int kHrFaultDelayMs = 10;
constexpr int kHrFaultException = 11;
constexpr int kHrFaultDrop = 12;
constexpr int kHrFaultStuckMask = 13;
constexpr int kHrFaultSpikeMask = 14;
constexpr int kHrFaultSpikeAmplitude = 15;
constexpr int kHrFaultSpikePeriod = 16;
// Pool 2 is record 1: 16-bit inputs at 100 + 8 + field, floats at 300 + 2 (8 + field),
// 16-bit holdings at 100 + 2 + field.
constexpr int kIrPool2Inflow = 108;
constexpr int kIrPool2Level = 110;
constexpr int kIrPool2Setting = 111;
constexpr int kIrPool2Setpoint = 112;
constexpr int kIrPool2LevelFloat = 320;
constexpr int kHrPool2Gate = 102;
constexpr int kIrPool3UpstreamLevel = 100 + 16 + 5;

constexpr std::uint16_t kStatusRunning = 1;
constexpr std::uint16_t kStatusHeartbeatLost = 2;
constexpr std::uint16_t kStatusLockstep = 4;
constexpr std::uint16_t kStatusFaultActive = 8;

const std::string kCanal = SourcePath("config/sim/asce-canal2.toml");
const std::string kPlc = SourcePath("config/sim/plc/asce2.toml");

float FloatAbcd(const std::vector<std::uint16_t>& r) { return modbus_get_float_abcd(r.data()); }

class ServeTest : public ::testing::Test {
 protected:
  void Start(std::vector<std::string> extra = {"--lockstep"}) {
    dir_ = TestDirectory(std::string("serve_") +
                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::vector<std::string> args = {"--canal", kCanal, "--plc", kPlc};
    args.insert(args.end(), extra.begin(), extra.end());
    server_ = std::make_unique<ServeProcess>(args, dir_ / "stderr.txt");
  }
  void TearDown() override {
    if (server_) {
      EXPECT_EQ(server_->Stop(), 0) << ReadFile(dir_ / "stderr.txt");
    }
  }
  int port() const { return server_->port(); }

  std::filesystem::path dir_;
  std::unique_ptr<ServeProcess> server_;
};

TEST_F(ServeTest, PrintsTheReadyLineAndStopsCleanlyOnSigterm) {
  Start();
  EXPECT_NE(server_->ready_line().find("canalsim: listening on 127.0.0.1:"), std::string::npos);
  EXPECT_NE(server_->ready_line().find("lockstep"), std::string::npos);
  EXPECT_GT(port(), 0);
  EXPECT_EQ(server_->Stop(), 0);
  EXPECT_NE(ReadFile(dir_ / "stderr.txt").find("stopped at plant time 0 s"), std::string::npos);
}

TEST_F(ServeTest, StopsCleanlyOnSigintWithMastersConnected) {
  Start({"--time-scale", "60"});
  Master m(port());
  EXPECT_EQ(m.TryReadInputs(0, 10), 0);
  EXPECT_EQ(server_->Stop(SIGINT), 0);
}

TEST_F(ServeTest, RegistersHoldTheSteadyState) {
  Start();
  Master m(port());
  EXPECT_EQ(m.Input(kIrStatus), kStatusRunning | kStatusLockstep);
  EXPECT_EQ(m.Input(kIrPoolCount), 8);
  // Pool 2 receives 11 m3/s minus pool 1's 1 m3/s offtake and holds its 2.1 m target depth.
  EXPECT_NEAR(m.Input(kIrPool2Inflow), 10000, 2);  // L/s; 2 L/s of steady-profile tolerance
  EXPECT_NEAR(m.Input(kIrPool2Level), 2100, 1);    // mm
  EXPECT_NEAR(FloatAbcd(m.Inputs(kIrPool2LevelFloat, 2)), 2.1, 1e-3);
  // The holding setpoint, the active setpoint and the actual opening agree at rest.
  const std::uint16_t gate = m.Holding(kHrPool2Gate);
  EXPECT_GT(gate, 500);
  EXPECT_EQ(m.Input(kIrPool2Setting), gate);
  EXPECT_EQ(m.Input(kIrPool2Setpoint), gate);
  // Lockstep: time moves only when told.
  EXPECT_EQ(m.Input(kIrStepCount), 0);
  m.Step(360);
  EXPECT_EQ(m.Input(kIrStepCount), 360);
  EXPECT_FLOAT_EQ(FloatAbcd(m.Inputs(kIrTimeFloat, 2)), 3600.0f);
  const auto t = m.Inputs(kIrTimeSeconds, 2);
  EXPECT_EQ((t[0] << 16) | t[1], 3600);
  EXPECT_EQ(m.Holding(1), 0);  // the step register reads 0 once the steps are done
  // Nothing changed, so the canal stays at rest (1 mm: the discrete steady state).
  EXPECT_NEAR(m.Input(kIrPool2Level), 2100, 1);
}

// Runs a shell command with a bounded time (30 s) and returns its stdout.
std::string Capture(const std::string& command) {
  // Per process: ctest may run this program's tests side by side.
  static int runs = 0;
  const std::string name =
      "serve_capture_" + std::to_string(getpid()) + "_" + std::to_string(++runs);
  return RunProgramWithin(command, TestDirectory(name), 30).out;
}

// mbpoll prints "[n]: \tvalue" per register.
std::string MbpollValue(const std::string& out, int reference) {
  const std::string key = "[" + std::to_string(reference) + "]:";
  const std::size_t at = out.find(key);
  if (at == std::string::npos) return "";
  const std::size_t end = out.find('\n', at);
  std::string v = out.substr(at + key.size(), end - at - key.size());
  v.erase(std::remove_if(v.begin(), v.end(), [](char c) { return c == ' ' || c == '\t'; }),
          v.end());
  return v;
}

TEST_F(ServeTest, MbpollReadsInputAndHoldingRegisters) {
  Start();
  const std::string base = "mbpoll -m tcp -a 1 -p " + std::to_string(port()) + " -1 -o 5 ";
  // 1-based reference 8 is protocol address 7, the pool count.
  const std::string system = Capture(base + "-t 3 -r 1 -c 10 127.0.0.1");
  EXPECT_EQ(MbpollValue(system, 1), std::to_string(kStatusRunning | kStatusLockstep)) << system;
  EXPECT_EQ(MbpollValue(system, 8), "8") << system;
  const std::string level = Capture(base + "-0 -t 3 -r 110 -c 8 127.0.0.1");
  EXPECT_NEAR(std::atoi(MbpollValue(level, 110).c_str()), 2100, 1) << level;
  const std::string level_float = Capture(base + "-0 -B -t 3:float -r 320 -c 1 127.0.0.1");
  EXPECT_NEAR(std::atof(MbpollValue(level_float, 320).c_str()), 2.1, 1e-3) << level_float;
  Master m(port());
  const std::string gate = Capture(base + "-0 -t 4 -r 102 -c 1 127.0.0.1");
  EXPECT_EQ(MbpollValue(gate, 102), std::to_string(m.Holding(kHrPool2Gate))) << gate;
  // A write through mbpoll reaches the PLC.
  Capture(base + "-0 -t 4 -r 102 127.0.0.1 1400");
  EXPECT_EQ(m.Input(kIrPool2Setpoint), 1400);
}

TEST_F(ServeTest, PymodbusGateSetpointMovesTheGateAtTheRateLimit) {
  Start();
  const auto run =
      RunProgram("timeout 60 /usr/bin/python3 " + SourcePath("tests/sim/serve_pymodbus.py") + " " +
                     std::to_string(port()),
                 dir_);
  EXPECT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("float_setpoint_ok"), std::string::npos) << run.out << run.err;
  std::printf("%s", run.out.c_str());
}

TEST_F(ServeTest, SetpointsAreClampedToThePlcLimits) {
  Start();
  Master m(port());
  m.Write(kHrPool2Gate, 9000);  // 9 m, above the 2.0 m limit of asce2.toml
  EXPECT_EQ(m.Holding(kHrPool2Gate), 2000);
  EXPECT_EQ(m.Input(kIrPool2Setpoint), 2000);
  EXPECT_TRUE(m.Input(kIrStatus) & 64);                     // status bit 6: last write clamped
  m.Write(kHrPool2Gate, static_cast<std::uint16_t>(-100));  // negative: below 0.05 m
  EXPECT_EQ(m.Holding(kHrPool2Gate), 50);
}

TEST_F(ServeTest, WriteAndReadInOneRequestReachesThePlc) {
  Start();
  Master m(port());
  const std::uint16_t value = 1400;
  std::uint16_t read[2];
  // Function code 23: write the gate setpoint, read the system status back.
  ASSERT_EQ(modbus_write_and_read_registers(m.ctx(), kHrPool2Gate, 1, &value, 0, 2, read), 2)
      << modbus_strerror(errno);
  EXPECT_EQ(m.Input(kIrPool2Setpoint), 1400);
  // Function code 22: mask write keeps the bits of the and-mask, sets the or-mask's others.
  m.Write(kHrFaultSpikePeriod, 0x00F0);
  ASSERT_EQ(modbus_mask_write_register(m.ctx(), kHrFaultSpikePeriod, 0x0030, 0x0001), 1);
  EXPECT_EQ(m.Holding(kHrFaultSpikePeriod), 0x0031);
}

TEST_F(ServeTest, HeartbeatTimeoutReturnsSetpointsToNominal) {
  Start();
  Master m(port());
  const std::uint16_t nominal = m.Holding(kHrPool2Gate);
  m.Write(kHrHeartbeat, 1);  // at t = 0
  m.Write(kHrPool2Gate, 1200);
  m.Step(29);  // t = 290 s < 300 s
  EXPECT_EQ(m.Input(kIrStatus) & kStatusHeartbeatLost, 0);
  EXPECT_EQ(m.Holding(kHrPool2Gate), 1200);
  m.Step(1);  // t = 300 s: timed out
  EXPECT_EQ(m.Input(kIrStatus) & kStatusHeartbeatLost, kStatusHeartbeatLost);
  EXPECT_EQ(m.Holding(kHrPool2Gate), nominal);
  EXPECT_EQ(m.Input(kIrPool2Setpoint), nominal);
  // Setpoint writes are ignored until the heartbeat changes again.
  m.Write(kHrPool2Gate, 1200);
  EXPECT_EQ(m.Holding(kHrPool2Gate), nominal);
  m.Write(kHrHeartbeat, 2);
  EXPECT_EQ(m.Input(kIrStatus) & kStatusHeartbeatLost, 0);
  m.Write(kHrPool2Gate, 1200);
  EXPECT_EQ(m.Holding(kHrPool2Gate), 1200);
}

TEST_F(ServeTest, ExceptionFaultAnswersEveryReadWithTheCode) {
  Start();
  Master m(port());
  m.Write(kHrFaultException, 4);  // slave device failure
  EXPECT_EQ(m.TryReadInputs(kIrStatus, 10), EMBXSFAIL);
  std::uint16_t r[1];
  EXPECT_EQ(modbus_read_registers(m.ctx(), kHrPool2Gate, 1, r), -1);
  EXPECT_EQ(errno, EMBXSFAIL);
  m.Write(kHrFaultException, 2);  // illegal data address; writes still work
  EXPECT_EQ(m.TryReadInputs(kIrStatus, 10), EMBXILADD);
  m.Write(kHrFaultException, 0);
  EXPECT_EQ(m.TryReadInputs(kIrStatus, 10), 0);
  // A real illegal address is still reported as such.
  EXPECT_EQ(m.TryReadInputs(60000, 2), EMBXILADD);
}

TEST_F(ServeTest, DelayFaultTimesOutAShortTimeoutMaster) {
  Start();
  Master impatient(port(), 0.2);
  Master patient(port(), 20.0);
  patient.Write(kHrFaultDelayMs, 1500);
  EXPECT_EQ(patient.Input(kIrFaults) & 1, 1);  // delayed but answered within 20 s
  EXPECT_EQ(impatient.TryReadInputs(kIrStatus, 10), ETIMEDOUT);
  patient.Write(kHrFaultDelayMs, 0);  // this write is itself delayed, then clears the fault
  EXPECT_EQ(patient.Input(kIrFaults) & 1, 0);
  // A fresh short-timeout connection gets its answers again.
  Master again(port(), 5.0);
  EXPECT_EQ(again.TryReadInputs(kIrStatus, 10), 0);
}

TEST_F(ServeTest, DropFaultClosesTheConnection) {
  Start();
  Master m(port());
  m.Write(kHrFaultDrop, 1);
  const int error = m.TryReadInputs(kIrStatus, 10);
  EXPECT_NE(error, 0);
  EXPECT_NE(error, ETIMEDOUT);  // closed, not silent
  m.Reconnect();
  EXPECT_EQ(m.TryReadInputs(kIrStatus, 10), 0);
  EXPECT_EQ(m.Holding(kHrFaultDrop), 0);  // one request was dropped, the fault is spent
}

TEST_F(ServeTest, StuckSensorFreezesTheLevelReading) {
  Start();
  Master m(port());
  const std::uint16_t frozen = m.Input(kIrPool2Level);
  const std::uint16_t pool3_before = m.Input(kIrPool3UpstreamLevel);
  m.Write(kHrFaultStuckMask, 1u << 1);  // record 1 = pool 2
  EXPECT_EQ(m.Input(kIrFaults) & 8, 8);
  EXPECT_TRUE(m.Input(kIrStatus) & kStatusFaultActive);
  m.Write(kHrPool2Gate, 800);  // close pool 2's gate (1.53 -> 0.8 m): its level rises
  // 30 min, feeding the 300 s heartbeat watchdog every 200 s so that the setpoint holds.
  for (int k = 1; k <= 9; ++k) {
    m.Write(kHrHeartbeat, static_cast<std::uint16_t>(k));
    m.Step(20);
    EXPECT_EQ(m.Input(kIrPool2Level), frozen);
  }
  // Pool 3 is not stuck and sees its inflow fall.
  const int pool3_after = m.Input(kIrPool3UpstreamLevel);
  m.Write(kHrFaultStuckMask, 0);
  const int pool2_after = m.Input(kIrPool2Level);
  std::printf("after 30 min: pool 2 level %d mm (stuck at %d), pool 3 upstream %d -> %d mm\n",
              pool2_after, frozen, pool3_before, pool3_after);
  EXPECT_LT(pool3_after, pool3_before - 20);
  // Mass balance: about 4 m3/s held back on 40,000 m2 of pool 2 for 1800 s would be 0.18 m,
  // less as the head on the gate grows and pool 1's submerged gate passes less (74 mm here);
  // 40 mm is far above the 1 mm of a canal at rest.
  EXPECT_GT(pool2_after, frozen + 40);
}

TEST_F(ServeTest, SpikingSensorAddsTheAmplitudeEveryOtherStep) {
  Start();
  Master m(port());
  m.WriteMany(kHrFaultSpikeMask, {1u << 1, 500, 2});  // pool 2, +500 mm, every 2nd step
  for (int k = 0; k < 6; ++k) {
    m.Step(1);
    const int steps = m.Input(kIrStepCount);
    const int level = m.Input(kIrPool2Level);
    // At rest the true level is 2100 mm (1 mm tolerance of the discrete steady state).
    EXPECT_NEAR(level, steps % 2 == 0 ? 2600 : 2100, 1) << "step " << steps;
  }
  m.Write(kHrFaultSpikeMask, 0);
  m.Step(2);
  EXPECT_NEAR(m.Input(kIrPool2Level), 2100, 1);
}

TEST_F(ServeTest, TwoClientsAtOnce) {
  Start();
  Master a(port());
  Master b(port());
  a.Write(kHrPool2Gate, 1300);
  EXPECT_EQ(b.Holding(kHrPool2Gate), 1300);
  b.Step(3);
  EXPECT_EQ(a.Input(kIrStepCount), 3);
  EXPECT_EQ(a.Inputs(300, 125), b.Inputs(300, 125));
  // Closing one connection leaves the other served.
  b.Reconnect();
  a.Step(1);
  EXPECT_EQ(b.Input(kIrStepCount), 4);
}

TEST_F(ServeTest, ScaledRealTimeAdvancesOnItsOwn) {
  Start({"--time-scale", "600"});  // a 10 s step every 16.7 ms
  Master m(port());
  EXPECT_EQ(m.Input(kIrStatus) & kStatusLockstep, 0);
  // Bounded: at most 60 s of polling for 3 steps that take 50 ms.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int steps = 0;
  while (steps < 3 && std::chrono::steady_clock::now() < deadline) {
    steps = m.Input(kIrStepCount);
  }
  EXPECT_GE(steps, 3);
}

TEST_F(ServeTest, ReadLatencyOf125Registers) {
  Start();
  Master m(port());
  // Reported, not asserted: loopback timing depends on the machine.
  std::vector<double> us;
  std::vector<std::uint16_t> r(125);
  for (int i = 0; i < 2000; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(modbus_read_input_registers(m.ctx(), 300, 125, r.data()), 125);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(us.begin(), us.end());
  std::printf("125-register read over loopback: median %.1f us, p90 %.1f us, p99 %.1f us\n",
              us[us.size() / 2], us[us.size() * 9 / 10], us[us.size() * 99 / 100]);
}

TEST(ServeCommand, ConfigErrorsExit78WithTheirLocation) {
  const auto dir = TestDirectory("serve_config_errors");
  WriteFile(dir / "bad.toml", "plant_step_s = 10\n[[pool]]\nname = \"2\"\nrate = 1\n");
  const auto run = RunProgram(CanalsimProgram() + " serve --canal " + kCanal + " --plc " +
                                  (dir / "bad.toml").string() + " --listen 127.0.0.1:0",
                              dir);
  EXPECT_EQ(run.exit_code, 78);
  // The column of an unknown key is its key or its value, depending on the reader version.
  EXPECT_THAT(run.err, ::testing::ContainsRegex("bad.toml:4:[0-9]+: unknown key 'pool.0..rate'"));
  const auto listen = RunProgram(
      CanalsimProgram() + " serve --canal " + kCanal + " --listen 127.0.0.1 --lockstep", dir);
  EXPECT_EQ(listen.exit_code, 78);
  EXPECT_NE(listen.err.find("--listen"), std::string::npos) << listen.err;
  const auto both = RunProgram(CanalsimProgram() + " serve --canal " + kCanal +
                                   " --listen 127.0.0.1:0 --lockstep --time-scale 60",
                               dir);
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("excludes"), std::string::npos) << both.err;
  const auto format = RunProgram(CanalsimProgram() + " serve --canal " + kCanal +
                                     " --listen 127.0.0.1:0 --rtu /dev/null --rtu-format 9X3",
                                 dir);
  EXPECT_EQ(format.exit_code, 78);
  EXPECT_NE(format.err.find("--rtu-format"), std::string::npos) << format.err;
  const auto check = RunProgram(
      CanalsimProgram() + " serve --canal " + kCanal + " --plc " + kPlc + " --check-config", dir);
  EXPECT_EQ(check.exit_code, 0) << check.err;
}

}  // namespace
}  // namespace canalid::testing
