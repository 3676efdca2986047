// `canalid dashboard` live: canalsim (ASCE canal 2 at 600 x), canalidd (the demo's configuration)
// and the dashboard on an LCM udpm bus of the test's own (a private network namespace), the page
// in headless Chromium read through the DevTools protocol.  The truths are what the test itself
// receives on the bus: the last sample's level, the experiment's state, the online model's
// parameters and the daemon's HEALTH counters (read back from /metrics by Python's reference
// parser).  The dashboard also outlives a restart of the daemon and malformed messages.
#include <gtest/gtest.h>
#include <signal.h>

#include <canalid/experiment_state_t.hpp>
#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "drivers/lcm/bus.h"
#include "drivers/lcm/lcm_bus.h"
#include "tests/dashboard/dashboard_test_support.h"
#include "tests/sim/serve_process.h"
#include "tests/support/child_process.h"
#include "tests/support/daemon_experiment_run.h"
#include "tests/support/headless_chromium.h"
#include "tests/support/http_client.h"
#include "tests/support/private_network.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr const char* kPrefix = "CANALID_ASCE2_";

std::string SourcePath(const std::string& relative) {
  return std::string(CANALID_SOURCE_DIR) + "/" + relative;
}

// What the test hears on the bus: the latest message of each kind.
struct BusTruth {
  explicit BusTruth(drivers::Bus& bus) {
    drivers::SubscribeMessage<canalid::sample_t>(
        bus, std::string(kPrefix) + "SAMPLE_.*",
        [this](const std::string&, const canalid::sample_t& m) { sample = m; });
    drivers::SubscribeMessage<canalid::health_t>(
        bus, std::string(kPrefix) + "HEALTH",
        [this](const std::string&, const canalid::health_t& m) { health[m.component] = m; });
    drivers::SubscribeMessage<canalid::experiment_state_t>(
        bus, std::string(kPrefix) + "EXPERIMENT_pool2",
        [this](const std::string&, const canalid::experiment_state_t& m) { experiment = m; });
    drivers::SubscribeMessage<canalid::model_snapshot_t>(
        bus, std::string(kPrefix) + "MODEL_pool2",
        [this](const std::string&, const canalid::model_snapshot_t& m) {
          models[m.model_kind + "/" + m.estimator] = m;
        });
  }
  double Channel(const std::string& name) const {
    for (std::size_t i = 0; i < sample.channel_names.size(); ++i) {
      if (sample.channel_names[i] == name) return sample.values[i];
    }
    return NAN;
  }
  canalid::sample_t sample;
  std::map<std::string, canalid::health_t> health;
  canalid::experiment_state_t experiment;
  std::map<std::string, canalid::model_snapshot_t> models;
};

// canalsim, the dashboard and canalidd in this test's private network.
class LiveRig {
 public:
  /// `start`: when the demo's experiment starts ("on_start" or "manual": not in this test).
  LiveRig(const std::string& name, const std::string& start)
      : dir_(TestDirectory(name)), bus_(Network()), truth_(bus_) {
    fs::create_directories(dir_ / "state");
    canal_ = std::make_unique<ServeProcess>(
        std::vector<std::string>{"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc",
                                 SourcePath("config/sim/plc/asce2.toml"), "--time-scale", "600"},
        dir_ / "canalsim.err");
    // The dashboard first, so it hears the daemon's CONFIG message at its start.
    dashboard_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{CanalidProgram(), "dashboard", "--lcm-url", kUrl, "--listen",
                                 "127.0.0.1:0"},
        std::vector<std::string>{}, dir_ / "dashboard.log");
    const std::string key = "serving http://127.0.0.1:";
    const std::string line = dashboard_->WaitForLine(key, 20000);
    if (line.empty()) throw std::runtime_error("no dashboard: " + dashboard_->output());
    port_ = std::stoi(line.substr(line.find(key) + key.size()));
    WriteFile(dir_ / "canalidd.toml",
              RewriteDaemonConfig(SourcePath("config/canalidd-asce2.toml"),
                                  {{"port", std::to_string(canal_->port())},
                                   {"state_directory", "\"" + (dir_ / "state").string() + "\""},
                                   {"start", "\"" + start + "\""}},
                                  ""));
    StartDaemon();
  }

  void StartDaemon() {
    daemon_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{std::string(CANALID_BINARY_DIR) + "/daemon/canalidd/canalidd",
                                 "--config", (dir_ / "canalidd.toml").string()},
        std::vector<std::string>{std::string("LCM_DEFAULT_URL=") + kUrl},
        dir_ / ("canalidd-" + std::to_string(++daemon_runs_) + ".log"));
  }

  // Pumps the test's bus until `done` holds or `seconds` pass.
  template <class F>
  bool PumpUntil(F done, double seconds) {
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::milliseconds(static_cast<int>(seconds * 1000));
    while (std::chrono::steady_clock::now() < deadline) {
      if (done()) return true;
      bus_.Handle(0.05);
    }
    return done();
  }
  void Pump(double seconds) {
    PumpUntil([] { return false; }, seconds);
  }

  json State() { return json::parse(HttpBody(HttpGet(port_, "/api/state")), nullptr, false); }

  const fs::path& dir() const { return dir_; }
  int port() const { return port_; }
  ChildProcess& daemon() { return *daemon_; }
  ChildProcess& dashboard() { return *dashboard_; }
  BusTruth& truth() { return truth_; }
  drivers::LcmBus& bus() { return bus_; }

 private:
  // Enters the private network before the bus is made (a member initializer runs first).
  static std::string Network() {
    const std::string problem = EnterPrivateNetwork();
    if (!problem.empty()) throw std::runtime_error(problem);
    return kUrl;
  }

  fs::path dir_;
  drivers::LcmBus bus_;
  BusTruth truth_;
  std::unique_ptr<ServeProcess> canal_;
  std::unique_ptr<ChildProcess> dashboard_;
  std::unique_ptr<ChildProcess> daemon_;
  int port_ = 0;
  int daemon_runs_ = 0;
};

// The page as a script reads it: reach pool2's level, phase, and the id model rows.
constexpr const char* kReadPage = R"JS((() => {
  const reach = document.querySelector('[data-reach="pool2"]');
  if (!reach) return null;
  const text = (role) => { const e = reach.querySelector(`[data-role="${role}"]`);
                           return e ? e.textContent : null; };
  const models = [...reach.querySelectorAll('tr[data-kind]')].map((tr) => ({
    kind: tr.dataset.kind, estimator: tr.dataset.estimator,
    samples: Number(tr.querySelector('[data-role="samples"]').textContent),
    params: Object.fromEntries([...tr.querySelectorAll('[data-param]')].map(
      (s) => [s.dataset.param, Number(s.dataset.value)]))}));
  return { level: text("level"), phase: text("phase"), band: text("band"), models,
           updates: Number(document.getElementById("updates").textContent),
           connection: document.getElementById("connection").textContent,
           charts: document.querySelectorAll('[data-chart] canvas').length };
})())JS";

json OnlineModel(const json& page, const std::string& kind) {
  for (const auto& m : page["models"]) {
    if (m["kind"] == kind && m["estimator"] != "batch") return m;
  }
  return nullptr;
}

TEST(DashboardLive, ChromiumShowsTheReachLevelPhaseAndModelsAsTheyUpdate) {
  std::unique_ptr<LiveRig> rig;
  try {
    rig = std::make_unique<LiveRig>("dashboard_live_page", "on_start");
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  HeadlessChromium browser;
  std::string error;
  ASSERT_TRUE(
      browser.Start("http://127.0.0.1:" + std::to_string(rig->port()) + "/", rig->dir(), &error))
      << error;

  // While the experiment excites: the reach, its level and band, the phase, the online model.
  json page;
  const bool shown = rig->PumpUntil(
      [&] {
        page = browser.Evaluate(kReadPage);
        return page.is_object() && page["phase"] == "exciting" &&
               OnlineModel(page, "id").is_object() && page["level"].is_string() &&
               page["level"] != "-" && page["charts"].get<int>() >= 3;
      },
      90);
  ASSERT_TRUE(shown) << page.dump() << "\n"
                     << browser.Evaluate("document.documentElement.outerHTML.slice(0, 4000)")
                     << "\n"
                     << rig->dashboard().output();
  EXPECT_EQ(page["band"], "1.900 .. 2.300");
  EXPECT_EQ(page["connection"], "live");
  const fs::path screenshot = rig->dir() / "dashboard.png";
  ASSERT_TRUE(browser.Screenshot(screenshot));
  EXPECT_EQ(ReadFile(screenshot).substr(1, 3), "PNG");
  // NOLINTNEXTLINE(concurrency-mt-unsafe): nothing sets the environment in this test
  if (const char* keep = std::getenv("CANALID_DASHBOARD_SCREENSHOT")) {
    fs::copy_file(screenshot, keep, fs::copy_options::overwrite_existing);
  }

  // It updates: more messages over the WebSocket, the online model's samples growing.
  const int updates = page["updates"];
  const int samples = OnlineModel(page, "id")["samples"];
  ASSERT_TRUE(rig->PumpUntil(
      [&] {
        page = browser.Evaluate(kReadPage);
        return page.is_object() && page["updates"].get<int>() > updates + 4 &&
               OnlineModel(page, "id")["samples"].get<int>() > samples;
      },
      30))
      << page.dump();

  // A HEALTH message of every component has come (every 10 s).
  ASSERT_TRUE(rig->PumpUntil([&] { return rig->truth().health.count("plc.asce2") == 1; }, 30));

  // The daemon frozen: the page then shows exactly what was last published.
  ASSERT_EQ(kill(rig->daemon().pid(), SIGSTOP), 0);
  rig->Pump(1.5);
  const BusTruth& truth = rig->truth();
  const double level = truth.Channel("pool2_level");
  const canalid::model_snapshot_t* online = nullptr;
  for (const auto& [key, m] : truth.models) {
    if (m.model_kind == "id" && m.estimator != "batch") online = &m;
  }
  ASSERT_NE(online, nullptr);
  const bool settled = rig->PumpUntil(
      [&] {
        page = browser.Evaluate(kReadPage);
        const json model = page.is_object() ? OnlineModel(page, "id") : json();
        return model.is_object() && model["samples"].get<std::int64_t>() == online->samples_used &&
               std::abs(std::stod(page["level"].get<std::string>()) - level) <= 0.0005 + 1e-12;
      },
      10);
  EXPECT_TRUE(settled) << page.dump() << " level " << level << " samples " << online->samples_used;
  const char* const states[] = {"idle",       "armed", "settling", "exciting",
                                "recovering", "done",  "aborted"};
  EXPECT_EQ(page["phase"], states[truth.experiment.state]);
  const json model = OnlineModel(page, "id");
  for (std::size_t i = 0; i < online->param_names.size(); ++i) {
    const double shown_value = model["params"][online->param_names[i]];
    EXPECT_NEAR(shown_value, online->param_values[i], 1e-12 * std::abs(online->param_values[i]))
        << online->param_names[i];
  }

  // /metrics, read by the reference parser, holds the daemon's last HEALTH counters.
  const std::vector<json> metrics =
      ParsedMetrics(HttpBody(HttpGet(rig->port(), "/metrics")), rig->dir());
  int compared = 0;
  for (const auto& [component, health] : truth.health) {
    for (std::size_t i = 0; i < health.counter_names.size(); ++i) {
      EXPECT_EQ(
          MetricValue(
              metrics, "canalid_health_counter_total",
              {{"site", kPrefix}, {"component", component}, {"name", health.counter_names[i]}}),
          static_cast<double>(health.counter_values[i]))
          << component << " " << health.counter_names[i];
      ++compared;
    }
  }
  EXPECT_GT(compared, 10);
  EXPECT_DOUBLE_EQ(MetricValue(metrics, "canalid_channel_value", {{"channel", "pool2_level"}}),
                   level);
  ASSERT_EQ(kill(rig->daemon().pid(), SIGCONT), 0);
}

// The rig with the experiment left manual, once the daemon's samples flow, and a page connected
// (its snapshot read).
class DashboardLiveWithPage : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      rig_ = std::make_unique<LiveRig>(
          std::string("dashboard_live_") +
              ::testing::UnitTest::GetInstance()->current_test_info()->name(),
          "manual");
    } catch (const std::exception& e) {
      FAIL() << e.what();
    }
    ASSERT_TRUE(rig_->PumpUntil([&] { return Sequence() > 20; }, 30)) << state_.dump();
    std::string error;
    ASSERT_TRUE(page_.Connect(rig_->port(), "/ws", &error)) << error;
    std::string text;
    ASSERT_TRUE(page_.Read(&text));
    EXPECT_EQ(json::parse(text)["type"], "snapshot");
  }
  // The dashboard's last sequence number of the PLC (-1 before any); its state kept in state_.
  std::int64_t Sequence() {
    state_ = rig_->State();
    if (!state_.is_object() || state_["sites"].empty()) return -1;
    const auto& sources = state_["sites"][0]["sources"];
    return sources.empty() ? -1 : sources[0]["sequence"].get<std::int64_t>();
  }

  std::unique_ptr<LiveRig> rig_;
  WebSocketClient page_;
  json state_;
};

TEST_F(DashboardLiveWithPage, MalformedMessagesAreCountedAndChangeNothing) {
  // Malformed messages on the daemon's channels: counted, ignored, nothing else changes.
  const std::vector<std::uint8_t> garbage(200, 0xA5);
  canalid::sample_t sample = rig_->truth().sample;
  std::vector<std::uint8_t> huge_count = Encoded(sample);
  huge_count.resize(40);  // the header and a count that claims far more than the bytes hold
  const std::vector<std::string> channels = {"SAMPLE_asce2", "MODEL_pool2", "EXPERIMENT_pool2",
                                             "HEALTH", "CONFIG"};
  for (const std::string& channel : channels) {
    ASSERT_TRUE(rig_->bus().Publish(kPrefix + channel, garbage));
  }
  ASSERT_TRUE(rig_->bus().Publish(std::string(kPrefix) + "SAMPLE_asce2", huge_count));
  const auto malformed = [&] {
    state_ = rig_->State();
    return state_.is_object() ? state_["messages"]["malformed"].get<int>() : -1;
  };
  ASSERT_TRUE(rig_->PumpUntil([&] { return malformed() == 6; }, 10)) << state_.dump();
  EXPECT_TRUE(rig_->dashboard().Running());
  EXPECT_FALSE(state_["sites"][0]["layout"].is_null()) << "the layout survives a bad CONFIG";
  EXPECT_EQ(state_["sites"].size(), 1U);
  EXPECT_EQ(state_["sites"][0]["sources"].size(), 1U);
  EXPECT_EQ(state_["sites"][0]["malformed"], 6);

  // The page connection goes on.
  std::string next;
  EXPECT_TRUE(page_.Read(&next));
  EXPECT_EQ(json::parse(next)["type"], "delta");
}

TEST_F(DashboardLiveWithPage, OutlivesTheDaemonsRestart) {
  std::string text;
  // The daemon restarts: the same page connection goes on with the new daemon's samples.
  const std::int64_t before = Sequence();
  ASSERT_EQ(rig_->daemon().Stop(SIGTERM, 20000), 0) << rig_->daemon().output();
  rig_->StartDaemon();
  ASSERT_TRUE(rig_->PumpUntil(
      [&] {
        const std::int64_t now = Sequence();
        return now >= 0 && now < before && now > 5;
      },
      30))
      << state_.dump();
  EXPECT_TRUE(rig_->dashboard().Running());
  // The deltas queued meanwhile, then new ones; bounded by 60 s.
  std::int64_t newest = -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (newest < 0 && std::chrono::steady_clock::now() < deadline) {
    ASSERT_TRUE(page_.Read(&text)) << "the page connection was lost";
    const json delta = json::parse(text);
    const auto& sources = delta["state"]["sites"][0]["sources"];
    if (delta["type"] == "delta" && !sources.empty() &&
        sources[0]["sequence"].get<std::int64_t>() < before) {
      newest = sources[0]["sequence"];
    }
  }
  EXPECT_GE(newest, 0) << "the page got the restarted daemon's samples";
}

}  // namespace
}  // namespace canalid::testing
