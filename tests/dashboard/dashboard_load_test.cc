// `canalid dashboard` under load, as a program: a log written by LCM's own writer (30 channels
// at 1 kHz, played in real time) is served to 50 pages at once; then to a few pages while one
// more client upgrades to a WebSocket and never reads, the dashboard's memory (VmRSS) measured
// against a control run whose per-client queue limit is too large to matter, so the measurement
// is shown to see the growth the limit prevents.
#include <gtest/gtest.h>
#include <sys/socket.h>

#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/dashboard/dashboard_test_support.h"
#include "tests/support/child_process.h"
#include "tests/support/http_client.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kChannels = 30;
constexpr int kSamples = 20000;  // 20 s at 1 kHz

void WriteLog(const fs::path& path) {
  TestLog log(path);
  const std::int64_t t0 = 1763700000000000;
  canalid::config_t config;
  config.utime = t0;
  config.text = ShippedConfigText("canalidd-asce2.toml");
  config.version = "test";
  log.Write("CANALID_ASCE2_CONFIG", config, t0);
  canalid::sample_t sample;
  sample.source = "asce2";
  sample.num_channels = kChannels;
  for (int c = 0; c < kChannels; ++c) {
    sample.channel_names.push_back(c == 0 ? "pool2_level" : "channel_" + std::to_string(c));
  }
  sample.values.assign(kChannels, 0.0);
  sample.quality.assign(kChannels, int8_t{canalid::sample_t::QUALITY_VALID});
  for (int i = 0; i < kSamples; ++i) {
    sample.utime = t0 + std::int64_t{1000} * (i + 1);
    sample.sequence = i;
    for (std::size_t c = 0; c < sample.values.size(); ++c) {
      sample.values[c] = 2.0 + 1e-3 * static_cast<double>((static_cast<std::size_t>(i) + c) % 100);
    }
    log.Write("CANALID_ASCE2_SAMPLE_asce2", sample, sample.utime);
  }
}

long RssKiB(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

struct LoadRun {
  long baseline_kib = 0;     ///< after the 50 pages have their snapshot, before the log ends
  long peak_kib = 0;         ///< the most while the log plays
  int pages_ok = 0;          ///< pages that loaded the page and dygraphs and got 20 updates
  double dropped_slow = -1;  ///< from /metrics
  double opened = -1;
};

// Plays `log` to `pages` pages at once (and, with `silent`, one client that never reads),
// sampling the dashboard's memory until the log has played.
LoadRun RunDashboard(const fs::path& dir, const fs::path& log, int queue_kib, int pages_count,
                     bool silent_client) {
  LoadRun run;
  ChildProcess dashboard(
      {CanalidProgram(), "dashboard", "--log", log.string(), "--listen", "127.0.0.1:0",
       "--update-period", "0.05", "--max-client-queue-kib", std::to_string(queue_kib)},
      {}, dir / ("dashboard-" + std::to_string(queue_kib) + ".log"));
  const std::string key = "serving http://127.0.0.1:";
  const std::string line = dashboard.WaitForLine(key, 20000);
  EXPECT_FALSE(line.empty()) << dashboard.output();
  if (line.empty()) return run;
  const int port = std::stoi(line.substr(line.find(key) + key.size()));

  // The client that never reads: a small receive buffer, the upgrade, then nothing.
  const int silent = silent_client ? ConnectLoopback(port) : -1;
  if (silent_client) {
    const int small = 4096;
    setsockopt(silent, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    const std::string upgrade = WebSocketUpgradeRequest("/ws");
    EXPECT_EQ(send(silent, upgrade.data(), upgrade.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(upgrade.size()));
  }

  // 50 pages at once: the page and dygraphs over HTTP, then the WebSocket's snapshot and 20
  // updates each.
  std::atomic<int> ok{0};
  // Pages that have their snapshot or have failed: the main thread waits for all of them.
  std::mutex settled_mutex;
  std::condition_variable settled_changed;
  int settled = 0;
  const auto settle = [&] {
    const std::lock_guard<std::mutex> lock(settled_mutex);
    ++settled;
    settled_changed.notify_all();
  };
  std::vector<std::thread> pages;
  pages.reserve(static_cast<std::size_t>(pages_count));
  for (int p = 0; p < pages_count; ++p) {
    pages.emplace_back([&] {
      const std::string html = HttpGet(port, "/");
      const std::string dygraphs = HttpGet(port, "/assets/dygraph.min.js");
      if (HttpStatus(html) != 200 || HttpStatus(dygraphs) != 200 ||
          HttpBody(dygraphs).size() !=
              fs::file_size("/usr/share/javascript/dygraphs/dygraph.min.js")) {
        settle();
        return;
      }
      WebSocketClient ws;
      std::string error, text;
      const bool snapshot = ws.Connect(port, "/ws", &error) && ws.Read(&text);
      settle();
      if (!snapshot) return;
      int updates = 0;
      // Counted, not parsed: 50 parsers at once would make the pages, not the server, the
      // bottleneck on a 2-core machine.
      while (updates < 20 && ws.Read(&text)) {
        updates += text.find(R"("type":"delta")") != std::string::npos ? 1 : 0;
      }
      if (updates == 20) ++ok;
      ws.Close();
    });
  }
  const auto start = std::chrono::steady_clock::now();
  {
    std::unique_lock<std::mutex> lock(settled_mutex);
    EXPECT_TRUE(settled_changed.wait_for(lock, std::chrono::seconds(20),
                                         [&] { return settled == pages_count; }))
        << settled << " of " << pages_count << " pages settled in 20 s";
  }
  run.baseline_kib = RssKiB(dashboard.pid());
  // Until the log has played (20 s of it), sampling the memory every 50 ms.
  while (dashboard.output().find("played:") == std::string::npos &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(40)) {
    run.peak_kib = std::max(run.peak_kib, RssKiB(dashboard.pid()));
    dashboard.WaitUntil([] { return false; }, 50);
  }
  for (auto& t : pages) t.join();
  run.pages_ok = ok;
  const auto metrics = ParsedMetrics(HttpBody(HttpGet(port, "/metrics")), dir);
  run.dropped_slow =
      MetricValue(metrics, "canalid_dashboard_http_total", {{"event", "websocket_dropped_slow"}});
  run.opened =
      MetricValue(metrics, "canalid_dashboard_http_total", {{"event", "websocket_opened"}});
  if (silent >= 0) close(silent);
  EXPECT_EQ(dashboard.Stop(SIGTERM, 10000), 0) << dashboard.output();
  return run;
}

TEST(DashboardLoad, FiftyPagesAtOnceLoadThePageAndGetTheirUpdates) {
  const fs::path dir = TestDirectory("dashboard_load_pages");
  const fs::path log = dir / "load.lcmlog";
  WriteLog(log);
  const LoadRun run = RunDashboard(dir, log, 8192, 50, false);
  EXPECT_EQ(run.pages_ok, 50);
  EXPECT_EQ(run.dropped_slow, 0.0);
  EXPECT_GE(run.opened, 50.0);
}

TEST(DashboardLoad, AClientThatNeverReadsIsDroppedAndMemoryStaysBounded) {
  const fs::path dir = TestDirectory("dashboard_load_silent");
  const fs::path log = dir / "load.lcmlog";
  WriteLog(log);
  const LoadRun bounded = RunDashboard(dir, log, 1024, 5, true);
  const LoadRun control = RunDashboard(dir, log, 1048576, 5, true);
  const long bounded_growth = bounded.peak_kib - bounded.baseline_kib;
  const long control_growth = control.peak_kib - control.baseline_kib;
  std::cout << "dashboard RSS growth with a client that never reads: " << bounded_growth
            << " KiB with --max-client-queue-kib 1024 (peak " << bounded.peak_kib << " KiB), "
            << control_growth << " KiB with 1 GiB (peak " << control.peak_kib << " KiB)\n";
  EXPECT_EQ(bounded.pages_ok, 5) << "the pages that read are served meanwhile";
  EXPECT_EQ(control.pages_ok, 5);
  EXPECT_EQ(bounded.dropped_slow, 1.0) << "the client that never reads, and only it";
  EXPECT_EQ(control.dropped_slow, 0.0);
#if defined(__SANITIZE_ADDRESS__)
  // Under AddressSanitizer (scripts/sanitize) the dashboard's RSS holds ASan's quarantine of
  // freed memory (256 MiB by default) and its shadow: 373 MB of growth with either limit, so
  // the bounds below, which are for the program as shipped, say nothing there. The drop itself
  // is checked above in every build.
  std::cout << "RSS bounds not checked under AddressSanitizer\n";
#else
  // The limit holds the client's queue at 1 MiB (plus the update being written); the rest is
  // the store filling (30 series x 7200 points x 16 B = 3.3 MiB) and the pages' own buffers.
  EXPECT_LT(bounded_growth, 16 * 1024);
  EXPECT_GT(control_growth, 2 * bounded_growth) << "the measurement sees the unbounded queue";
#endif
}

}  // namespace
}  // namespace canalid::testing
