// The dashboard application's routes, in process (no socket): the page and its assets are the
// files they were embedded from, nothing else is served, the API answers, and bad inputs at
// start are named.
#include "daemon/dashboard/dashboard_app.h"

#include <gtest/gtest.h>

#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/dashboard/dashboard_test_support.h"
#include "tests/drivers/lcm_test_messages.h"
#include "tests/support/run_program.h"

namespace canalid::dashboard {
namespace {

namespace fs = std::filesystem;
using canalid::testing::Encoded;
using canalid::testing::ReadFile;

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A log of the demo's CONFIG and three samples.
fs::path WriteLog(const fs::path& dir) {
  fs::path path = dir / "small.lcmlog";
  canalid::testing::TestLog log(path);
  canalid::config_t config;
  config.text = canalid::testing::ShippedConfigText("canalidd-asce2.toml");
  log.Write("CANALID_ASCE2_CONFIG", config, 1763700000000000);
  for (int i = 1; i <= 3; ++i) {
    log.Write("CANALID_ASCE2_SAMPLE_asce2", testing::MakeSample(i), 1763700000000000 + i);
  }
  return path;
}

class DashboardAppTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = canalid::testing::TestDirectory(
        "dashboard_app_" +
        std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    DashboardOptions options;
    options.log_path = WriteLog(dir_).string();
    options.speed = 0.0;
    options.port = 0;
    app_ = std::make_unique<DashboardApp>(io_, options);
    app_->Start();
    // Plays the log: its 4 messages, bounded by 10 s.
    for (int i = 0; i < 1000 && app_->store().counters().used < 4; ++i) {
      io_.run_for(std::chrono::milliseconds(10));
    }
    ASSERT_EQ(app_->store().counters().used, 4);
  }
  fs::path dir_;
  boost::asio::io_context io_;
  std::unique_ptr<DashboardApp> app_;
};

TEST_F(DashboardAppTest, ThePageAndItsAssetsAreTheFilesTheyWereBuiltFrom) {
  const fs::path page = fs::path(CANALID_SOURCE_DIR) / "daemon/dashboard/page";
  const fs::path dygraphs = "/usr/share/javascript/dygraphs";
  const std::vector<std::tuple<std::string, fs::path, std::string>> expected = {
      {"/", page / "index.html", "text/html; charset=utf-8"},
      {"/index.html", page / "index.html", "text/html; charset=utf-8"},
      {"/assets/dashboard.js", page / "dashboard.js", "text/javascript; charset=utf-8"},
      {"/assets/dashboard.css", page / "dashboard.css", "text/css; charset=utf-8"},
      {"/assets/dygraph.min.js", dygraphs / "dygraph.min.js", "text/javascript; charset=utf-8"},
      {"/assets/dygraph.min.css", dygraphs / "dygraph.min.css", "text/css; charset=utf-8"}};
  for (const auto& [target, file, type] : expected) {
    const drivers::HttpResponse response = app_->Get(target);
    EXPECT_EQ(response.status, 200) << target;
    EXPECT_EQ(response.content_type, type) << target;
    EXPECT_EQ(response.body, Bytes(file)) << target << " is not " << file;
  }
  // Nothing else: no file serving, no path tricks.
  for (const char* target : {"/assets/", "/assets/../index.html", "/../etc/passwd", "/etc/passwd",
                             "/assets/dygraph.js", "//index.html", "/index.html/", "/api/x"}) {
    EXPECT_EQ(app_->Get(target).status, 404) << target;
  }
}

TEST_F(DashboardAppTest, TheApiAnswersFromWhatThePlayedLogHeld) {
  const drivers::HttpResponse state = app_->Get("/api/state?pretty=no");
  ASSERT_EQ(state.status, 200);
  EXPECT_EQ(state.content_type, "application/json");
  const auto json = nlohmann::json::parse(state.body);
  ASSERT_EQ(json["sites"].size(), 1U);
  const auto& site = json["sites"][0];
  EXPECT_EQ(site["prefix"], "CANALID_ASCE2_");
  EXPECT_EQ(site["layout"]["reaches"][0]["level_max_m"], 2.3);
  EXPECT_EQ(site["sources"][0]["sequence"], 3);
  int series = 0;
  for (const auto& channel : site["sources"][0]["channels"]) {
    if (channel["name"] == "level_m") series = channel["series"];
  }
  const auto points =
      nlohmann::json::parse(app_->Get("/api/series/" + std::to_string(series)).body);
  ASSERT_EQ(points["points"].size(), 3U) << points.dump();         // the three samples' levels
  EXPECT_EQ(points["points"][2][1], static_cast<double>(1.234F));  // history is f32
  for (const std::string bad : {"abc", "999999", "1x", "", "-1"}) {
    const auto response = app_->Get("/api/series/" + bad);
    EXPECT_EQ(response.status, 404) << bad;
    EXPECT_NE(response.body.find("no series"), std::string::npos) << bad;
  }
  const auto snapshot = nlohmann::json::parse(app_->Get("/api/snapshot").body);
  EXPECT_EQ(snapshot["type"], "snapshot");
  EXPECT_TRUE(nlohmann::json::parse(app_->Get("/api").body).contains("endpoints"));
  const drivers::HttpResponse metrics = app_->Get("/metrics");
  EXPECT_EQ(metrics.content_type, "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_NE(metrics.body.find("canalid_channel_value{site=\"CANALID_ASCE2_\""), std::string::npos);
}

TEST(DashboardAppStart, NamesTheFileOrLogItCannotUse) {
  const fs::path dir = canalid::testing::TestDirectory("dashboard_app_start");
  boost::asio::io_context io;
  DashboardOptions missing_log;
  missing_log.log_path = (dir / "absent.lcmlog").string();
  try {
    DashboardApp app(io, missing_log);
    FAIL() << "opened a missing log";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("absent.lcmlog"), std::string::npos) << e.what();
  }
  canalid::testing::WriteFile(dir / "bad.toml", "[lcm]\nchannel_prefix = 7\n");
  DashboardOptions bad_config;
  bad_config.log_path = WriteLog(dir).string();
  bad_config.config_paths = {(dir / "bad.toml").string()};
  try {
    DashboardApp app(io, bad_config);
    FAIL() << "took a bad configuration";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("channel_prefix"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canalid::dashboard
