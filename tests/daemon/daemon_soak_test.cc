// Soak: canalidd against canalsim serve (ASCE canal 2, pool 2) for many simulated days, with an
// experiment started by an authenticated command every simulated day (excitation on for about 6.5
// plant hours, then off), in a private network namespace whose udpm bus the test listens to.
//   CANALID_SOAK_DAYS   simulated days (default 2, as in the test command; docs/reliability.md
//                       records a 30-day run), at 3000 plant s per wall s: 28.8 wall s a day.
// Truths checked: the daemon's resident memory and open descriptors level off after the first
// day (read from /proc, not from the daemon), its error counters stay at zero but for what its
// short response timeouts explain, every experiment it is asked for runs to an identified model
// (or is aborted by a timed-out setpoint write, which the safety rule requires) and gives the
// gate back at the nominal it read,
// and no model it publishes is absurd without a flag saying so (an area outside 0.1-10 x the IDZ
// area of pool 2, 34113 m2, or a delay at an edge of the bank). A table of the run goes to
// test-output/daemon_soak/soak.csv.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>

#include "tests/sim/serve_process.h"
#include "tests/support/child_process.h"
#include "tests/support/daemon_experiment_run.h"
#include "tests/support/private_network.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kTimeScale = 3000.0;  // plant s per wall s
constexpr double kPollPeriod = 0.02;   // wall s: Ts = 60 plant s, as the demo
constexpr double kDayWall = 86400.0 / kTimeScale;
constexpr double kIdzArea = 34113.0;  // m2, pool 2 backwater (domain/README.md)
constexpr double kMaxDelay = 1400.0;  // s, max_delay_s of config/canalidd-asce2.toml
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr const char* kPrefix = "CANALID_ASCE2_";

int SoakDays() {
  const char* text =
      std::getenv("CANALID_SOAK_DAYS");  // NOLINT(concurrency-mt-unsafe): no threads yet
  if (text == nullptr) return 2;
  char* end = nullptr;
  const long days = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || days < 2 || days > 365) return -1;
  return static_cast<int>(days);
}

/// Resident set (kB) and open descriptors of a process, read from /proc.
struct Footprint {
  long rss_kb = -1;
  long fds = -1;
};
Footprint FootprintOf(pid_t pid) {
  Footprint f;
  const std::string proc = "/proc/" + std::to_string(pid);
  std::istringstream status(ReadFile(proc + "/status"));
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) f.rss_kb = std::stol(line.substr(6));
  }
  // The least of three counts: a state file open for a moment (a model being saved) is no leak.
  for (int attempt = 0; attempt < 3; ++attempt) {
    std::error_code ec;
    long n = 0;
    for (fs::directory_iterator it(proc + "/fd", ec), end; !ec && it != end; it.increment(ec)) ++n;
    if (!ec && (f.fds < 0 || n < f.fds)) f.fds = n;
  }
  return f;
}

/// What the test hears on the bus.
class BusListener {
 public:
  explicit BusListener(lcm::LCM& lcm) {
    lcm.subscribe(std::string(kPrefix) + "HEALTH", &BusListener::OnHealth, this);
    lcm.subscribe(std::string(kPrefix) + "MODEL_pool2", &BusListener::OnModel, this);
  }
  void OnHealth(const lcm::ReceiveBuffer*, const std::string&, const canalid::health_t* m) {
    auto& counters = health[m->component];
    for (int i = 0; i < m->num_counters; ++i) {
      counters[m->counter_names[static_cast<std::size_t>(i)]] =
          m->counter_values[static_cast<std::size_t>(i)];
    }
    ++health_messages;
  }
  void OnModel(const lcm::ReceiveBuffer*, const std::string&, const canalid::model_snapshot_t* m) {
    ++models;
    if (m->model_kind != "id") return;
    std::map<std::string, double> p, sd;
    for (std::size_t i = 0; i < static_cast<std::size_t>(m->num_params); ++i) {
      p[m->param_names[i]] = m->param_values[i];
      sd[m->param_names[i]] = m->param_std_devs[i];
    }
    const double area = p.count("area_m2") != 0 ? p["area_m2"] : NAN;
    const double delay = p.count("delay_s") != 0 ? p["delay_s"] : NAN;
    const bool absurd =
        !(area >= 0.1 * kIdzArea && area <= 10.0 * kIdzArea) || !(delay > 0.0 && delay < kMaxDelay);
    if (m->estimator == "batch") {
      ++batch_models;
      batch_areas.push_back(area);
    } else {
      ++online_id;
      if (absurd) (m->flags != 0 ? flagged_absurd : unflagged_absurd)++;
      if (absurd && m->flags == 0 && first_unflagged.empty()) {
        first_unflagged = "area " + std::to_string(area) + " m2, delay " + std::to_string(delay) +
                          " s, samples " + std::to_string(m->samples_used) + ", area sd " +
                          std::to_string(sd["area_m2"]) + " m2, excitation " +
                          std::to_string(m->excitation) + ", condition " +
                          std::to_string(m->condition_number);
      }
    }
  }

  std::map<std::string, std::map<std::string, int64_t>> health;
  long health_messages = 0;
  long models = 0;
  long online_id = 0;
  long batch_models = 0;
  long flagged_absurd = 0;
  long unflagged_absurd = 0;
  std::string first_unflagged;
  std::vector<double> batch_areas;
};

struct Row {
  double wall_s;
  double day;
  Footprint footprint;
  int64_t polls;
};

TEST(DaemonSoak, DaysOfPollingAndExperimentsLeaveMemoryDescriptorsAndCountersFlat) {
  const int days = SoakDays();
  ASSERT_GT(days, 0) << "CANALID_SOAK_DAYS must be a whole number of days in 2..365";
  const std::string network = EnterPrivateNetwork();
  ASSERT_TRUE(network.empty()) << network;
  ASSERT_TRUE(fs::exists(CommandProgram())) << CommandProgram();
  const fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "daemon_soak";
  fs::remove_all(dir);
  fs::create_directories(dir / "state");

  // The PLC's watchdog at 3000 x would be 0.1 wall s (300 plant s): ten times that, so that a
  // loaded test machine does not trip it; the watchdog is not under test here.
  const fs::path plc = Asce2PlcWithWatchdog(dir, "3000.0");
  ASSERT_FALSE(plc.empty()) << "config/sim/plc/asce2.toml has no heartbeat_timeout_s = 300.0";
  ServeProcess canal({"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc", plc.string(),
                      "--time-scale", "3000"},
                     dir / "canalsim.err");

  const fs::path key = dir / "command.key";
  std::ofstream(key) << "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff\n";
  ::chmod(key.c_str(), 0600);
  std::ostringstream commands;
  commands << "true\nkey_file = \"" << key.string() << "\"";
  const std::string config_text = RewriteDaemonConfig(
      SourcePath("config/canalidd-asce2.toml"),
      {{"port", std::to_string(canal.port())},
       {"state_directory", "\"" + (dir / "state").string() + "\""},
       {"time_scale", "3000.0"},
       {"period_s", "0.02"},       // heartbeat
       {"poll_period_s", "0.02"},  // Ts = 60 plant s
       {"response_timeout_s", "0.015"},
       {"start", "\"manual\""},
       {"max_sample_gap_periods", "25.0"},  // 0.5 wall s, as the other live tests
       {"url", std::string("\"") + kUrl + "\""},
       {"enabled", commands.str()}},
      "");
  std::ofstream(dir / "canalidd.toml") << config_text;
  ChildProcess daemon({DaemonProgram(), "--config", (dir / "canalidd.toml").string()}, {},
                      dir / "canalidd.log");
  ASSERT_FALSE(daemon.WaitForLine("commands enabled", 20000).empty()) << daemon.output();

  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  BusListener bus(lcm);
  const auto start = Clock::now();
  auto wall = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  std::vector<Row> rows;
  int started = 0;
  double next_sample = 0.0;
  while (wall() < days * kDayWall) {
    lcm.handleTimeout(50);
    daemon.Drain();  // its log, so that it never blocks on a full pipe
    ASSERT_TRUE(daemon.Running()) << daemon.output();
    // One experiment a day, a tenth of a day in.
    if (started < days && wall() >= (started + 0.1) * kDayWall) {
      ChildProcess command(
          {CommandProgram(), "--key", key.string(), "--channel", std::string(kPrefix) + "COMMAND",
           "--reach", "pool2", "--sender", "soak", "start"},
          {std::string("LCM_DEFAULT_URL=") + kUrl}, dir / "command.log");
      EXPECT_EQ(command.WaitExit(10000), 0) << command.output();
      ++started;
    }
    if (wall() >= next_sample) {
      const auto plc_health = bus.health.find("plc.asce2");
      rows.push_back({wall(), wall() / kDayWall, FootprintOf(daemon.pid()),
                      plc_health == bus.health.end() ? -1 : plc_health->second["polls"]});
      next_sample += kDayWall / 24.0;  // hourly in plant time
      if (rows.size() % 24 == 0) {     // progress, once a simulated day
        std::printf("soak: day %.0f: RSS %ld kB, fds %ld, polls %lld, models %ld\n",
                    rows.back().day, rows.back().footprint.rss_kb, rows.back().footprint.fds,
                    static_cast<long long>(rows.back().polls), bus.models);
        std::fflush(stdout);
      }
    }
  }
  const Footprint before_stop = FootprintOf(daemon.pid());
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();
  // The health message published on the way out.
  for (int i = 0; i < 20; ++i) lcm.handleTimeout(50);

  std::ofstream csv(dir / "soak.csv");
  csv << "wall_s,day,rss_kb,fds,polls\n";
  for (const Row& r : rows) {
    csv << r.wall_s << "," << r.day << "," << r.footprint.rss_kb << "," << r.footprint.fds << ","
        << r.polls << "\n";
  }

  // Memory and descriptors: the largest after day 1 against the value at the end of day 1.
  const auto day_one =
      std::find_if(rows.begin(), rows.end(), [](const Row& r) { return r.day >= 1.0; });
  ASSERT_NE(day_one, rows.end());
  long rss_max = 0, fds_max = 0, fds_min = 1 << 20;
  for (auto it = day_one; it != rows.end(); ++it) {
    rss_max = std::max(rss_max, it->footprint.rss_kb);
    fds_max = std::max(fds_max, it->footprint.fds);
    fds_min = std::min(fds_min, it->footprint.fds);
  }
  const long rss_day_one = day_one->footprint.rss_kb;
  std::printf(
      "soak: %d days, %d experiments started; RSS %ld kB at 1 h, %ld kB after day 1, "
      "%ld kB at most after it, %ld kB at the end; fds %ld..%ld; %ld health messages, "
      "%ld models (%ld online id, %ld batch), %ld flagged absurd\n",
      days, started, rows.front().footprint.rss_kb, rss_day_one, rss_max, before_stop.rss_kb,
      fds_min, fds_max, bus.health_messages, bus.models, bus.online_id, bus.batch_models,
      bus.flagged_absurd);
  // 2 MiB: allocator slack and the state files' buffers; a leak of one sample's worth a poll
  // (50 Hz x 30 days) would be gigabytes.
  EXPECT_LE(rss_max - rss_day_one, 2048) << "resident memory grows after day 1";
  EXPECT_EQ(fds_max, fds_min) << "open descriptors change after day 1";

  // Counters: no reconnect or failed write but those timeouts explain (below), no reply fault but
  // the late replies that timeouts leave, and timeouts (a 15 ms response timeout on a shared
  // machine) in at most 1 poll in 1000
  // (10 in a short run: a few polls of the 2-day run may meet a busy moment of the test command).
  // At most a fifth of the polls may be skipped as overruns of the 20 ms period on a busy machine.
  ASSERT_EQ(bus.health.count("plc.asce2"), 1U) << "no PLC health heard";
  const auto& plc_counters = bus.health.at("plc.asce2");
  const int64_t polls = plc_counters.at("polls");
  EXPECT_GT(polls, static_cast<int64_t>(0.8 * days * kDayWall / kPollPeriod));
  const int64_t timeouts = plc_counters.at("read_errors.timeout");
  const int64_t timeout_budget = std::max<int64_t>(10, polls / 1000);
  EXPECT_LE(timeouts, timeout_budget);
  // What those timeouts cause by design, and nothing more: three in a row drop the link (the
  // poller's timeouts_before_reconnect), and the heartbeat writes that meet a dropped link or time
  // out themselves fail, within the same budget. (Zero was asserted here, and a loaded test
  // machine failed it: 8 timeouts, 2 reconnects, 6 failed heartbeat writes, nothing aborted.)
  constexpr int64_t kTimeoutsBeforeReconnect = 3;
  // A late reply is skipped by the next exchange and counted as a transaction-id fault; the
  // request it answered timed out, a read (a read timeout) or a heartbeat write (a failed write).
  const int64_t writes_failed = plc_counters.at("writes_failed");
  for (const auto& [name, value] : plc_counters) {
    if (name == "bad_replies.transaction_id") {
      EXPECT_LE(value, timeouts + writes_failed)
          << name << ": " << timeouts << " read timeouts, " << writes_failed << " failed writes";
    } else if (name == "reconnects") {
      EXPECT_LE(value, timeouts / kTimeoutsBeforeReconnect) << name;
    } else if (name == "writes_failed") {
      EXPECT_LE(value, timeout_budget) << name;
    } else if ((name.rfind("read_errors.", 0) == 0 && name != "read_errors.timeout") ||
               name.rfind("bad_replies.", 0) == 0 || name == "connect_failures") {
      EXPECT_EQ(value, 0) << name;
    }
  }
  std::printf("soak: %lld polls, %lld timeouts, %lld overruns, %lld samples dropped\n",
              static_cast<long long>(polls), static_cast<long long>(timeouts),
              static_cast<long long>(plc_counters.at("overruns")),
              static_cast<long long>(plc_counters.at("samples_dropped")));

  // Every experiment identified the pool, or was aborted by the one fault this run may meet, and
  // gave the gate back.
  const std::string log = daemon.output();
  auto count = [&](const std::string& what) {
    long n = 0;
    for (std::size_t at = log.find(what); at != std::string::npos; at = log.find(what, at + 1)) ++n;
    return n;
  };
  // A setpoint write that times out (15 ms, as the reads) aborts its experiment: the safety rule
  // (any fault during an experiment restores the nominal) working, not a soak failure. It happened
  // in 1 of 5 runs on an idle machine; it counts as a failed write within the timeout budget
  // above. No experiment may be aborted for any other reason, and at least one must identify.
  const long write_aborts = count("reach pool2: experiment aborted (setpoint write failed)");
  EXPECT_LE(write_aborts, count("reach pool2: setpoint write failed (timeout)"));
  EXPECT_EQ(count("experiment aborted"), write_aborts) << log.substr(0, 4000);
  EXPECT_EQ(count("reach pool2: identified {"), started - write_aborts) << log.substr(0, 4000);
  EXPECT_LT(write_aborts, started) << log.substr(0, 4000);
  // The nominal the daemon read from the PLC at start is the one it restores after each.
  const std::string read_marker = "reach pool2: nominal setpoint ";
  const std::size_t read_at = log.find(read_marker);
  const std::size_t read_end = log.find(" (read from the PLC)", read_at);
  ASSERT_NE(read_end, std::string::npos) << log.substr(0, 4000);
  const std::string nominal =
      log.substr(read_at + read_marker.size(), read_end - read_at - read_marker.size());
  // Each experiment ends ("done" or "aborted") with the nominal written back and confirmed by the
  // PLC, before the next start (or the end of the log). The write at the start of settling is
  // confirmed too unless the first excitation write supersedes it first (settling lasts 10 polls,
  // 0.2 wall s, and a loaded machine delayed that write's answer past it once), so it is counted
  // as at most one per experiment. No restore is to another value.
  const std::string restored = read_marker + nominal + " restored";
  long ends_restored = 0;
  for (const char* end : {"reach pool2: experiment done", "reach pool2: experiment aborted"}) {
    for (std::size_t at = log.find(end); at != std::string::npos; at = log.find(end, at + 1)) {
      const std::size_t next_start = log.find("starting the experiment", at);
      const std::size_t restore_at = log.find(restored, at);
      if (restore_at != std::string::npos && restore_at < next_start) ++ends_restored;
    }
  }
  EXPECT_EQ(ends_restored, started) << log.substr(0, 4000);
  EXPECT_LE(count(restored), 2 * started) << log.substr(0, 4000);
  EXPECT_EQ(count(" restored"), count(restored)) << "a restore to another value";
  EXPECT_EQ(bus.unflagged_absurd, 0) << "first: " << bus.first_unflagged;
  EXPECT_GT(bus.online_id, 0);
  for (const double area : bus.batch_areas) {
    EXPECT_GT(area, 0.1 * kIdzArea);
    EXPECT_LT(area, 10.0 * kIdzArea);
  }
}

}  // namespace
}  // namespace canalid::testing
