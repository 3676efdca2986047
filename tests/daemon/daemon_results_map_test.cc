// canalidd's results register map, live: the demo's configuration (ASCE canal 2, pool 2, designed
// experiment at 600 x) against canalsim serve, with [results] listen on a free port.  While the
// experiment runs, SCADA-like masters read the map: libmodbus, pymodbus and mbpoll; 50 libmodbus
// masters poll it without pause until the end.  The truths: what the daemon published on LCM (its
// log, read afterwards): each slot read in one request equals the message with the same
// samples_used (f32 of the double); the experiment's phase; the refusal of writes.
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include "core/results/results_layout.h"
#include "tests/sim/serve_process.h"
#include "tests/support/child_process.h"
#include "tests/support/daemon_experiment_run.h"
#include "tests/support/loopback_port.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;

float F32(const std::uint16_t* words) { return modbus_get_float_abcd(words); }

// One slot read in one request (the server copies it under the image's lock: consistent).
struct Slot {
  std::vector<std::uint16_t> words;
  bool published() const { return words[core::kSlotPublished] == 1; }
  std::uint32_t samples() const {
    return (std::uint32_t{words[core::kSlotSamples]} << 16) | words[core::kSlotSamples + 1];
  }
  float Value(const core::ResultsKind& kind, const std::string& name) const {
    for (std::size_t i = 0; i < kind.params.size(); ++i) {
      if (kind.params[i] == name) {
        return F32(&words[core::kResultsSlotHeaderWords + core::kResultsWordsPerParam * i]);
      }
    }
    ADD_FAILURE() << kind.name << " has no parameter " << name;
    return NAN;
  }
};

Slot ReadSlot(modbus_t* ctx, const std::string& kind_name, bool batch) {
  const core::ResultsKind& kind = *core::FindResultsKind(kind_name);
  Slot slot;
  slot.words.resize(static_cast<std::size_t>(kind.words()));
  const int at = core::ResultsSlotAddress(0, kind, batch);
  // At most 125 registers per request: every slot of the demo's kinds (id, idz) fits one.
  EXPECT_EQ(modbus_read_input_registers(ctx, at, kind.words(), slot.words.data()), kind.words())
      << modbus_strerror(errno);
  return slot;
}

// The first message of `channel` in the log with this kind, estimator class and samples_used.
std::optional<canalid::model_snapshot_t> Published(const fs::path& log_path,
                                                   const std::string& channel,
                                                   const std::string& kind, bool batch,
                                                   std::uint32_t samples) {
  for (const canalid::model_snapshot_t& m : ModelMessagesIn(log_path, channel)) {
    if (m.model_kind == kind && core::IsBatchEstimator(m.estimator) == batch &&
        m.samples_used == samples) {
      return m;
    }
  }
  return std::nullopt;
}

// Every parameter of the message equals the slot's, as f32 (NaN where the message has NaN).
void ExpectSlotEquals(const Slot& slot, const std::string& kind_name,
                      const canalid::model_snapshot_t& m) {
  const core::ResultsKind& kind = *core::FindResultsKind(kind_name);
  ASSERT_GT(m.num_params, 1);
  for (int i = 0; i < m.num_params; ++i) {
    const auto at = static_cast<std::size_t>(i);
    const float expected = static_cast<float>(m.param_values[at]);
    const float got = slot.Value(kind, m.param_names[at]);
    if (std::isnan(expected)) {
      EXPECT_TRUE(std::isnan(got)) << kind_name << " " << m.param_names[at];
    } else {
      EXPECT_EQ(got, expected) << kind_name << " " << m.param_names[at];
    }
  }
  EXPECT_EQ(slot.words[core::kSlotFlags], m.flags);
  EXPECT_EQ(slot.words[core::kSlotUnmapped], 0);
  // The parameters the message does not name are NaN in the slot.
  const auto names_end = m.param_names.begin() + m.num_params;
  for (const std::string& name : kind.params) {
    if (std::find(m.param_names.begin(), names_end, name) == names_end) {
      EXPECT_TRUE(std::isnan(slot.Value(kind, name))) << kind_name << " " << name;
    }
  }
}

// Masters polling the reach's status block every 20 ms, as a SCADA scan would, until stopped; the
// destructor stops and joins them (also when an assertion returns early). The scan period is a
// wait on the stop signal, so Stop() ends every master at once.
class Pollers {
 public:
  Pollers(int port, int count) {
    for (int i = 0; i < count; ++i) {
      threads_.emplace_back([this, port] {
        modbus_t* c = modbus_new_tcp("127.0.0.1", port);
        modbus_set_response_timeout(c, 5, 0);
        if (modbus_connect(c) != 0) {
          failures_.fetch_add(1);
        } else {
          std::uint16_t words[125];
          std::unique_lock<std::mutex> lock(mutex_);
          while (!stop_) {
            lock.unlock();
            const bool ok =
                modbus_read_registers(c, core::ResultsReachAddress(0), 125, words) == 125;
            (ok ? reads_ : failures_).fetch_add(1);
            lock.lock();
            stopped_.wait_for(lock, std::chrono::milliseconds(20), [this] { return stop_; });
          }
        }
        modbus_close(c);
        modbus_free(c);
      });
    }
  }
  ~Pollers() { Stop(); }
  Pollers(const Pollers&) = delete;
  Pollers& operator=(const Pollers&) = delete;
  void Stop() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    stopped_.notify_all();
    for (std::thread& t : threads_) {
      if (t.joinable()) t.join();
    }
  }
  long reads() const { return reads_.load(); }
  long failures() const { return failures_.load(); }

 private:
  std::mutex mutex_;
  std::condition_variable stopped_;
  bool stop_ = false;  // guarded by mutex_
  std::atomic<long> reads_{0}, failures_{0};
  std::vector<std::thread> threads_;
};

TEST(DaemonResultsMap, ScadaMastersReadWhatTheDaemonPublishes) {
  const fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "daemon_results_map";
  fs::remove_all(dir);
  fs::create_directories(dir / "state");
  ServeProcess canal({"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc",
                      SourcePath("config/sim/plc/asce2.toml"), "--time-scale", "600"},
                     dir / "canalsim.err");
  const std::string config =
      RewriteDaemonConfig(SourcePath("config/canalidd-asce2.toml"),
                          {{"port", std::to_string(canal.port())},
                           {"state_directory", "\"" + (dir / "state").string() + "\""}},
                          "") +
      "\n[results]\nlisten = \"127.0.0.1:0\"\n";
  WriteFile(dir / "canalidd.toml", config);
  const fs::path log_path = dir / "run.lcmlog";
  ChildProcess daemon({std::string(CANALID_BINARY_DIR) + "/daemon/canalidd/canalidd", "--config",
                       (dir / "canalidd.toml").string()},
                      {"LCM_DEFAULT_URL=file://" + log_path.string() + "?mode=w"},
                      dir / "canalidd.log");
  const std::string key = "on 127.0.0.1:";
  const std::string serving = daemon.WaitForLine("results map: serving 1 reach(es) " + key, 20000);
  ASSERT_FALSE(serving.empty()) << daemon.output();
  const int port = std::stoi(serving.substr(serving.find(key) + key.size()));

  modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
  modbus_set_response_timeout(ctx, 5, 0);
  ASSERT_EQ(modbus_connect(ctx), 0) << modbus_strerror(errno);

  // 50 masters poll the reach status and the online id slot until the experiment ends.
  Pollers pollers(port, 50);

  // While exciting: the phase, its progress and the comms status as a SCADA sees them.
  ASSERT_FALSE(daemon.WaitForLine("reach pool2: experiment exciting", 60000).empty())
      << daemon.output();
  const int base = core::ResultsReachAddress(0);
  std::uint16_t status[core::kReachStatusWords] = {};
  // The map takes the new phase at its next update after the log line (under load, a read at
  // once can still see "settling", 2): read until it shows exciting (bounded; the designed
  // experiment excites for minutes of wall time after the line).
  EXPECT_TRUE(daemon.WaitUntil(
      [&] {
        return modbus_read_input_registers(ctx, base, core::kReachStatusWords, status) ==
                   core::kReachStatusWords &&
               status[core::kReachExperimentState] == 3;
      },
      10000, 50))
      << "reach status word " << status[core::kReachExperimentState];
  const float progress = F32(status + core::kReachProgress);
  EXPECT_GT(progress, 0.0f);
  EXPECT_LT(progress, 1.0f);
  // Wall seconds (the experiment ends within the 120 s this test waits for it; in plant seconds
  // at 600 x it would read hours).
  EXPECT_GT(F32(status + core::kReachTimeLeft), 0.0f);
  EXPECT_LT(F32(status + core::kReachTimeLeft), 120.0f);
  EXPECT_EQ(status[core::kReachCommsStatus], 0);
  EXPECT_GE(F32(status + core::kReachLevel), 1.9f);
  EXPECT_LE(F32(status + core::kReachLevel), 2.3f);
  EXPECT_EQ(status[0], ('p' << 8) | 'o');
  // The online id bank publishes once its estimate is valid: wait for it (bounded, and over at
  // once should the daemon exit).
  Slot online;
  EXPECT_TRUE(daemon.WaitUntil(
      [&] {
        online = ReadSlot(ctx, "id", false);
        return online.published();
      },
      60000, 100));
  ASSERT_TRUE(online.published());

  // mbpoll during the experiment: the online id delay (f32, high word first), a whole number of
  // samples of 60 plant s within the bank's 0..1400 s.
  const int online_delay = core::ResultsSlotAddress(0, *core::FindResultsKind("id"), false) +
                           core::kResultsSlotHeaderWords;
  const ProgramRun mb_online = RunProgramWithin("mbpoll -m tcp -a 1 -p " + std::to_string(port) +
                                                    " -1 -o 5 -0 -B -t 3:float -c 1 -r " +
                                                    std::to_string(online_delay) + " 127.0.0.1",
                                                dir, 30);
  const std::size_t value_at = mb_online.out.find("]:");
  ASSERT_NE(value_at, std::string::npos) << mb_online.out << mb_online.err;
  const double delay = std::stod(mb_online.out.substr(value_at + 2));
  EXPECT_GE(delay, 0.0) << mb_online.out;
  EXPECT_LE(delay, 1400.0) << mb_online.out;
  EXPECT_EQ(std::fmod(delay, 60.0), 0.0) << mb_online.out;

  // pymodbus during the experiment: the same words by function 3 and 4, writes refused.
  const ProgramRun py = RunProgramWithin(
      "/usr/bin/python3 " + SourcePath("tests/drivers/results_map_pymodbus.py") + " " +
          std::to_string(port) + " " +
          std::to_string(core::ResultsSlotAddress(0, *core::FindResultsKind("id"), false)) + " 42",
      dir, 60);
  ASSERT_EQ(py.exit_code, 0) << py.out << py.err;
  const nlohmann::json pj = nlohmann::json::parse(py.out);
  EXPECT_EQ(pj["write_exception"].get<int>(), 1);
  EXPECT_EQ(pj["holding"][0].get<int>(), 1);  // published

  ASSERT_FALSE(daemon.WaitForLine("reach pool2: experiment done", 120000).empty())
      << daemon.output();
  pollers.Stop();
  const Slot batch_id = ReadSlot(ctx, "id", true);
  const Slot batch_idz = ReadSlot(ctx, "idz", true);
  const Slot last_online = ReadSlot(ctx, "id", false);
  ASSERT_TRUE(batch_id.published());
  ASSERT_TRUE(batch_idz.published());
  const std::string mbpoll =
      "mbpoll -m tcp -a 1 -p " + std::to_string(port) + " -1 -o 5 -0 -B -t 3:float -c 1 -r " +
      std::to_string(core::ResultsSlotAddress(0, *core::FindResultsKind("id"), true) +
                     core::kResultsSlotHeaderWords + 4) +
      " 127.0.0.1";
  const ProgramRun mb = RunProgramWithin(mbpoll, dir, 30);
  std::uint16_t done[1];
  ASSERT_EQ(modbus_read_input_registers(ctx, base + core::kReachExperimentState, 1, done), 1);
  EXPECT_EQ(done[0], 5);
  modbus_close(ctx);
  modbus_free(ctx);

  // A reload (SIGHUP) restarts the map with the daemon: the models it persisted are back at once
  // in the batch slots (estimator 5, persisted), with the same values.
  const std::size_t before = daemon.output().size();
  kill(daemon.pid(), SIGHUP);
  const std::string again =
      daemon.WaitForLine("results map: serving 1 reach(es) " + key, 20000, before);
  ASSERT_FALSE(again.empty()) << daemon.output();
  // Logged once the state directory is loaded.
  ASSERT_FALSE(daemon.WaitForLine("running: ", 20000, before).empty()) << daemon.output();
  modbus_t* reloaded =
      modbus_new_tcp("127.0.0.1", std::stoi(again.substr(again.find(key) + key.size())));
  modbus_set_response_timeout(reloaded, 5, 0);
  ASSERT_EQ(modbus_connect(reloaded), 0) << modbus_strerror(errno);
  const Slot persisted_id = ReadSlot(reloaded, "id", true);
  modbus_close(reloaded);
  modbus_free(reloaded);
  EXPECT_EQ(persisted_id.words[core::kSlotEstimator], 5);
  const core::ResultsKind& id_kind = *core::FindResultsKind("id");
  for (const char* name : {"delay_s", "area_m2"}) {
    EXPECT_EQ(persisted_id.Value(id_kind, name), batch_id.Value(id_kind, name)) << name;
  }

  // A reload that moves the map to an address in use is refused before the daemon stops.
  const LoopbackListener busy = ListenOnLoopback();
  ASSERT_GE(busy.fd, 0);
  std::string moved = config;
  const std::string listen_line = "listen = \"127.0.0.1:0\"";
  moved.replace(moved.find(listen_line), listen_line.size(),
                "listen = \"127.0.0.1:" + std::to_string(busy.port) + "\"");
  WriteFile(dir / "canalidd.toml", moved);
  const std::size_t before_busy = daemon.output().size();
  kill(daemon.pid(), SIGHUP);
  EXPECT_FALSE(daemon
                   .WaitForLine("cannot listen on 127.0.0.1:" + std::to_string(busy.port), 20000,
                                before_busy)
                   .empty())
      << daemon.output();
  EXPECT_EQ(daemon.output().find("reloading the configuration", before_busy), std::string::npos);
  EXPECT_TRUE(daemon.Running());
  close(busy.fd);
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();

  EXPECT_EQ(pollers.failures(), 0);
  EXPECT_GT(pollers.reads(), 50);
  // Each slot is the message it was copied from (the LCM log is the daemon's record).
  const std::string channel = "CANALID_ASCE2_MODEL_pool2";
  for (const auto& [slot, kind, is_batch] :
       {std::tuple{static_cast<const Slot*>(&online), "id", false},
        std::tuple{&last_online, "id", false}, std::tuple{&batch_id, "id", true},
        std::tuple{&batch_idz, "idz", true}}) {
    const auto m = Published(log_path, channel, kind, is_batch, slot->samples());
    ASSERT_TRUE(m.has_value()) << kind << (is_batch ? " batch" : " online") << " samples "
                               << slot->samples();
    ExpectSlotEquals(*slot, kind, *m);
  }
  // mbpoll prints the batch area (parameter 1 of id) with 6 significant digits.
  const auto area = static_cast<double>(batch_id.Value(*core::FindResultsKind("id"), "area_m2"));
  const std::string needle = "]:";
  const std::size_t at = mb.out.find(needle);
  ASSERT_NE(at, std::string::npos) << mb.out << mb.err;
  EXPECT_NEAR(std::stod(mb.out.substr(at + needle.size())), area, 1e-5 * area) << mb.out;
}

}  // namespace
}  // namespace canalid::testing
