// `canalid dashboard` as a user runs it: each option has the effect its --help claims (seen in
// /api, /metrics or on the socket), and bad invocations are named with exit 2.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/dashboard/dashboard_test_support.h"
#include "tests/support/child_process.h"
#include "tests/support/http_client.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::int64_t kT0 = 1763700000000000;

// A log of `samples` samples of PLC asce2 (channel pool2_level), `step_s` apart; with
// `config`, the daemon's CONFIG message first.
fs::path WriteLog(const fs::path& path, int samples, double step_s, bool config) {
  TestLog log(path);
  if (config) {
    canalid::config_t message;
    message.utime = kT0;
    message.text = ShippedConfigText("canalidd-asce2.toml");
    log.Write("CANALID_ASCE2_CONFIG", message, kT0);
  }
  canalid::sample_t sample;
  sample.source = "asce2";
  sample.num_channels = 1;
  sample.channel_names = {"pool2_level"};
  sample.quality = {canalid::sample_t::QUALITY_VALID};
  for (int i = 0; i < samples; ++i) {
    sample.utime = kT0 + static_cast<std::int64_t>(step_s * 1e6 * i);
    sample.sequence = i;
    sample.values = {2.0 + 0.001 * i};
    log.Write("CANALID_ASCE2_SAMPLE_asce2", sample, sample.utime);
  }
  return path;
}

// `canalid dashboard ARGS --listen 127.0.0.1:0`, running, with the port it serves.
class Dashboard {
 public:
  Dashboard(const fs::path& dir, std::vector<std::string> args) {
    std::vector<std::string> argv = {CanalidProgram(), "dashboard", "--listen", "127.0.0.1:0"};
    argv.insert(argv.end(), args.begin(), args.end());
    child_ =
        std::make_unique<ChildProcess>(argv, std::vector<std::string>{}, dir / "dashboard.log");
    const std::string key = "serving http://127.0.0.1:";
    const std::string line = child_->WaitForLine(key, 20000);
    if (!line.empty()) port_ = std::stoi(line.substr(line.find(key) + key.size()));
  }
  int port() const { return port_; }
  ChildProcess& child() { return *child_; }
  json Get(const std::string& target) {
    return json::parse(HttpBody(HttpGet(port_, target)), nullptr, false);
  }
  // Waits (bounded) until the log has been played.
  bool Played(int timeout_ms) { return !child_->WaitForLine("played:", timeout_ms).empty(); }

 private:
  std::unique_ptr<ChildProcess> child_;
  int port_ = 0;
};

int SeriesOf(const json& state, const std::string& channel) {
  for (const auto& c : state["sites"][0]["sources"][0]["channels"]) {
    if (c["name"] == channel) return c["series"];
  }
  return 0;
}

TEST(DashboardCli, SpeedPacesTheLog) {
  const fs::path dir = TestDirectory("dashboard_cli_speed");
  const fs::path log = WriteLog(dir / "100s.lcmlog", 11, 10.0, false);  // 100 s of log
  {
    Dashboard fast(dir, {"--log", log.string(), "--speed", "50"});  // 2 s
    ASSERT_GT(fast.port(), 0) << fast.child().output();
    EXPECT_TRUE(fast.Played(30000)) << fast.child().output();
  }
  Dashboard slow(dir, {"--log", log.string(), "--speed", "1"});  // 100 s: not within 3 s
  ASSERT_GT(slow.port(), 0);
  EXPECT_FALSE(slow.Played(3000)) << slow.child().output();
  EXPECT_LT(slow.Get("/api/state")["messages"]["used"].get<int>(), 11);
}

TEST(DashboardCli, MaxPointsAndHistoryHoursBoundEachSeries) {
  const fs::path dir = TestDirectory("dashboard_cli_history");
  const fs::path log = WriteLog(dir / "100.lcmlog", 100, 1.0, false);  // 100 samples, 1 s apart
  const auto points_kept = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"--log", log.string(), "--speed", "0"});
    Dashboard d(dir, args);
    EXPECT_TRUE(d.Played(20000)) << d.child().output();
    const int id = SeriesOf(d.Get("/api/state"), "pool2_level");
    return d.Get("/api/series/" + std::to_string(id))["points"].size();
  };
  EXPECT_EQ(points_kept({}), 100U);
  EXPECT_EQ(points_kept({"--max-points", "10"}), 10U);
  // 0.01 h = 36 s: the newest point and those at most 36 s before it.
  EXPECT_EQ(points_kept({"--history-hours", "0.01"}), 37U);
}

TEST(DashboardCli, ConfigGivesTheLayoutBeforeTheDaemonsConfigMessage) {
  const fs::path dir = TestDirectory("dashboard_cli_config");
  const fs::path log = WriteLog(dir / "no-config.lcmlog", 3, 1.0, false);
  WriteFile(dir / "asce2.toml", ShippedConfigText("canalidd-asce2.toml"));
  Dashboard without(dir, {"--log", log.string(), "--speed", "0"});
  ASSERT_TRUE(without.Played(20000));
  EXPECT_TRUE(without.Get("/api/state")["sites"][0]["layout"].is_null());
  Dashboard with(
      dir, {"--log", log.string(), "--speed", "0", "--config", (dir / "asce2.toml").string()});
  ASSERT_TRUE(with.Played(20000));
  const json layout = with.Get("/api/state")["sites"][0]["layout"];
  EXPECT_EQ(layout["source"], (dir / "asce2.toml").string());
  EXPECT_EQ(layout["reaches"][0]["level_min_m"], 1.9);
}

TEST(DashboardCli, MaxConnectionsAndAllowHost) {
  const fs::path dir = TestDirectory("dashboard_cli_limits");
  const fs::path log = WriteLog(dir / "one.lcmlog", 1, 1.0, true);
  Dashboard d(dir, {"--log", log.string(), "--max-connections", "2", "--allow-host",
                    "Canalid.Plant.Example"});
  ASSERT_GT(d.port(), 0);
  const auto status_for_host = [&](const std::string& host) {
    return HttpStatus(RawExchange(
        d.port(), "GET /api HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n"));
  };
  EXPECT_EQ(status_for_host("canalid.plant.example"), 200);
  EXPECT_EQ(status_for_host("localhost:8080"), 200);
  EXPECT_EQ(status_for_host("other.example"), 403);
  const int a = ConnectLoopback(d.port());
  const int b = ConnectLoopback(d.port());
  ASSERT_TRUE(d.child().WaitUntil(
      [&] {
        // A third connection is accepted and closed at once while the two are held.
        const int c = ConnectLoopback(d.port());
        SetSocketTimeouts(c, 5.0);
        char byte = 0;
        const bool closed = recv(c, &byte, 1, 0) == 0;
        close(c);
        return closed;
      },
      20000, 100));
  close(a);
  close(b);
  std::string reply;  // once the server has seen the two close
  ASSERT_TRUE(d.child().WaitUntil(
      [&] { return HttpStatus(reply = HttpGet(d.port(), "/metrics")) == 200; }, 20000, 50));
  const auto metrics = ParsedMetrics(HttpBody(reply), dir);
  EXPECT_GE(
      MetricValue(metrics, "canalid_dashboard_http_total", {{"event", "connections_refused"}}),
      1.0);
}

TEST(DashboardCli, UpdatePeriodPacesThePageUpdates) {
  const fs::path dir = TestDirectory("dashboard_cli_update");
  const fs::path log = WriteLog(dir / "one.lcmlog", 1, 1.0, true);
  const auto updates_in_2s = [&](const std::string& period) {
    Dashboard d(dir, {"--log", log.string(), "--update-period", period});
    WebSocketClient ws;
    std::string error, text;
    EXPECT_TRUE(ws.Connect(d.port(), "/ws", &error, 2.0)) << error;
    EXPECT_TRUE(ws.Read(&text));  // the snapshot
    int updates = 0;
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (std::chrono::steady_clock::now() < end && ws.Read(&text)) ++updates;
    return updates;
  };
  EXPECT_GE(updates_in_2s("0.05"), 5);
  EXPECT_EQ(updates_in_2s("30"), 0);  // the first update comes after 30 s
}

TEST(DashboardCli, BadInvocationsAreNamedWithExit2) {
  const fs::path dir = TestDirectory("dashboard_cli_bad");
  const fs::path log = WriteLog(dir / "one.lcmlog", 1, 1.0, true);
  WriteFile(dir / "bad.toml", "[lcm]\nchannel_prefix = 7\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--listen nowhere", "--listen 'nowhere'"},
      {"--listen 127.0.0.1:99999", "--listen '127.0.0.1:99999'"},
      {"--speed 2", "--speed is for --log"},
      {"--log " + log.string() + " --config " + (dir / "bad.toml").string(), "bad.toml"},
      {"--log " + (dir / "absent.lcmlog").string(), "absent.lcmlog"},
      {"--lcm-url 'bogus://x'", "bogus://x"},
      {"--log " + log.string() + " --max-points 5", "--max-points"},
  };
  for (const auto& [args, named] : cases) {
    const ProgramRun run = RunProgramWithin(CanalidProgram() + " dashboard " + args, dir, 30);
    EXPECT_EQ(run.exit_code, 2) << args << "\n" << run.err;
    EXPECT_NE(run.err.find(named), std::string::npos) << args << "\n" << run.err;
  }
  // A busy port is named too.
  Dashboard first(dir, {"--log", log.string()});
  const ProgramRun busy =
      RunProgramWithin(CanalidProgram() + " dashboard --log " + log.string() +
                           " --listen 127.0.0.1:" + std::to_string(first.port()),
                       dir, 30);
  EXPECT_EQ(busy.exit_code, 2) << busy.err;
  EXPECT_NE(busy.err.find("cannot listen on 127.0.0.1:" + std::to_string(first.port())),
            std::string::npos)
      << busy.err;
}

}  // namespace
}  // namespace canalid::testing
