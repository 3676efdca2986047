// The dashboard's store of canalidd's messages, its JSON and its /metrics: routing by channel
// prefix, malformed input, bounded history, deltas, and the metrics read back by Python's
// reference Prometheus parser.
#include "daemon/dashboard/dashboard_store.h"

#include <gtest/gtest.h>

#include <canalid/config_t.hpp>

#include <cmath>
#include <deque>
#include <fstream>
#include <random>
#include <sstream>

#include "daemon/config/config_loader.h"
#include "daemon/dashboard/dashboard_json.h"
#include "daemon/dashboard/dashboard_metrics.h"
#include "tests/dashboard/dashboard_test_support.h"
#include "tests/drivers/lcm_test_messages.h"

namespace canalid::dashboard {
namespace {

using canalid::testing::Encoded;
using canalid::testing::MakeExperiment;
using canalid::testing::MakeHealth;
using canalid::testing::MakeModel;
using canalid::testing::MakeSample;
using canalid::testing::MetricValue;
using canalid::testing::ParsedMetrics;
using canalid::testing::ShippedConfigText;

TEST(DashboardStore, RoutesEachMessageToItsSiteByChannelPrefix) {
  DashboardStore store;
  EXPECT_EQ(store.OnMessage("SITE1_SAMPLE_plc.pool2", Encoded(MakeSample(1))), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("SITE1_MODEL_pool2", Encoded(MakeModel())), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("SITE1_EXPERIMENT_pool2", Encoded(MakeExperiment())), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("SITE1_HEALTH", Encoded(MakeHealth())), Ingest::kUsed);
  // A second daemon on the same bus, its prefix ending in a word the first one uses.
  EXPECT_EQ(store.OnMessage("B_CANALID_SAMPLE_other", Encoded(MakeSample(7))), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("SITE1_COMMAND", Encoded(MakeSample(1))), Ingest::kIgnored);
  EXPECT_EQ(store.OnMessage("SITE1_SAMPLE_", Encoded(MakeSample(1))), Ingest::kIgnored);
  EXPECT_EQ(store.OnMessage("heartbeat", {}), Ingest::kIgnored);

  ASSERT_EQ(store.sites().size(), 2U);
  const SiteState& site = store.sites().at("SITE1_");
  ASSERT_EQ(site.sources.count("plc.pool2"), 1U);
  const SourceState& source = site.sources.at("plc.pool2");
  EXPECT_EQ(source.status, MakeSample(1).status);
  EXPECT_DOUBLE_EQ(source.channels.at("level_m").value, 1.234);
  // Only the valid channel got a point; the others keep their quality and no point.
  EXPECT_EQ(source.channels.at("level_m").series->ring.size(), 1U);
  EXPECT_EQ(source.channels.at("flow_m3s").series->ring.size(), 0U);
  EXPECT_EQ(source.channels.at("flow_m3s").quality,
            int8_t{canalid::sample_t::QUALITY_OUT_OF_RANGE});
  const ReachState& reach = site.reaches.at("pool2");
  ASSERT_TRUE(reach.experiment.has_value());
  EXPECT_EQ(reach.experiment->step, MakeExperiment().step);
  const ModelTrack& track = reach.models.at("id/rls-directional");
  EXPECT_EQ(track.latest.param_values, MakeModel().param_values);
  EXPECT_FLOAT_EQ(track.params.at("delay_s")->ring.at(0).sd, 12.5F);
  EXPECT_EQ(site.health.count(MakeHealth().component), 1U);
  EXPECT_EQ(store.sites().at("B_CANALID_").sources.count("other"), 1U);
  EXPECT_EQ(store.counters().used, 5);
  EXPECT_EQ(store.counters().ignored, 3);
}

TEST(DashboardStore, MalformedMessagesAreCountedAndChangeNothing) {
  DashboardStore store;
  ASSERT_EQ(store.OnMessage("S_SAMPLE_plc", Encoded(MakeSample(1))), Ingest::kUsed);
  std::vector<std::uint8_t> truncated = Encoded(MakeSample(2));
  truncated.resize(truncated.size() / 2);
  const std::vector<std::uint8_t> garbage(64, 0xFF);
  EXPECT_EQ(store.OnMessage("S_SAMPLE_plc", truncated), Ingest::kMalformed);
  EXPECT_EQ(store.OnMessage("S_SAMPLE_plc", garbage), Ingest::kMalformed);
  EXPECT_EQ(store.OnMessage("S_MODEL_pool2", garbage), Ingest::kMalformed);
  EXPECT_EQ(store.OnMessage("S_EXPERIMENT_pool2", Encoded(MakeSample(3))), Ingest::kMalformed);
  EXPECT_EQ(store.OnMessage("S_HEALTH", {}), Ingest::kMalformed);
  EXPECT_EQ(store.OnMessage("S_CONFIG", garbage), Ingest::kMalformed);
  const SiteState& site = store.sites().at("S_");
  EXPECT_EQ(site.malformed, 6);
  EXPECT_EQ(store.counters().malformed, 6);
  EXPECT_EQ(site.sources.at("plc").sequence, 1);
  EXPECT_TRUE(site.reaches.empty());
  EXPECT_TRUE(site.health.empty());
  // Names that are not UTF-8 reach the JSON replaced, never as an exception.
  canalid::sample_t odd = MakeSample(4);
  odd.channel_names[0] = "level\xff\xfe";
  ASSERT_EQ(store.OnMessage("S_SAMPLE_plc", Encoded(odd)), Ingest::kUsed);
  EXPECT_NO_THROW(DumpJson(StateJson(store, 0)));
}

TEST(DashboardStore, JunkOnTheBusMakesNoSiteAndAKeywordPrefixFindsItsSite) {
  StoreLimits limits;
  limits.max_sites = 2;
  DashboardStore store(limits);
  // Other programs' channels that happen to end in a keyword, their bytes not ours.
  for (const char* channel : {"ROBOT_HEALTH", "CAM_SAMPLE_front", "X_MODEL_a", "Y_CONFIG"}) {
    EXPECT_EQ(store.OnMessage(channel, std::vector<std::uint8_t>(32, 0x11)), Ingest::kMalformed);
  }
  EXPECT_TRUE(store.sites().empty());
  // A daemon whose prefix holds a keyword: its HEALTH names it, then its samples follow it.
  EXPECT_EQ(store.OnMessage("MODEL_RIG_HEALTH", Encoded(MakeHealth())), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("MODEL_RIG_SAMPLE_plc", Encoded(MakeSample(1))), Ingest::kUsed);
  EXPECT_EQ(store.OnMessage("MODEL_RIG_MODEL_pool2", Encoded(MakeModel())), Ingest::kUsed);
  ASSERT_EQ(store.sites().size(), 1U);
  const SiteState& site = store.sites().at("MODEL_RIG_");
  EXPECT_EQ(site.sources.count("plc"), 1U);
  EXPECT_EQ(site.reaches.count("pool2"), 1U);
  // A second real daemon still has a place.
  EXPECT_EQ(store.OnMessage("B_HEALTH", Encoded(MakeHealth())), Ingest::kUsed);
}

TEST(DashboardStore, NamesBeyondTheLimitAreRefusedPerMap) {
  StoreLimits limits;
  limits.max_names = 3;
  DashboardStore store(limits);
  for (int s = 0; s < 5; ++s) {
    const Ingest result =
        store.OnMessage("S_SAMPLE_plc" + std::to_string(s), Encoded(MakeSample(1)));
    EXPECT_EQ(result, s < 3 ? Ingest::kUsed : Ingest::kRefused) << s;
  }
  canalid::health_t health = MakeHealth();
  for (int c = 0; c < 5; ++c) {
    health.component = "component" + std::to_string(c);
    store.OnMessage("S_HEALTH", Encoded(health));
  }
  const SiteState& site = store.sites().at("S_");
  EXPECT_EQ(site.sources.size(), 3U);
  EXPECT_EQ(site.health.size(), 3U);
  EXPECT_EQ(store.counters().refused, 4);
}

TEST(DashboardStore, SequenceGapsAreCountedAsDroppedSamples) {
  DashboardStore store;
  for (const int sequence : {1, 2, 5, 6, 10}) {
    store.OnMessage("S_SAMPLE_plc", Encoded(MakeSample(sequence)));
  }
  EXPECT_EQ(store.sites().at("S_").sources.at("plc").dropped, 2 + 3);
  EXPECT_EQ(store.sites().at("S_").sources.at("plc").samples, 5);
}

TEST(DashboardStore, TheConfigMessageGivesReachesAndSafetyBandsAndABadOneIsReported) {
  DashboardStore store;
  canalid::config_t config;
  config.utime = 1;
  config.path = "/etc/canalid/canalidd.toml";
  config.version = "9.9.9";
  config.text = ShippedConfigText("canalidd-asce2.toml");
  ASSERT_EQ(store.OnMessage("CANALID_ASCE2_CONFIG", Encoded(config)), Ingest::kUsed);
  const SiteState& site = store.sites().at("CANALID_ASCE2_");
  ASSERT_TRUE(site.layout.has_value());
  EXPECT_EQ(site.layout->version, "9.9.9");
  ASSERT_EQ(site.layout->reaches.size(), 1U);
  const ReachLayout& pool2 = site.layout->reaches[0];
  EXPECT_EQ(pool2.name, "pool2");
  EXPECT_EQ(pool2.level, "pool2_level");
  EXPECT_EQ(pool2.inflow, "pool2_inflow");
  EXPECT_DOUBLE_EQ(pool2.level_min_m, 1.9);
  EXPECT_DOUBLE_EQ(pool2.level_max_m, 2.3);

  config.text = "[daemon]\nunknown_key = 1\n";
  EXPECT_EQ(store.OnMessage("CANALID_ASCE2_CONFIG", Encoded(config)), Ingest::kUsed);
  EXPECT_NE(site.layout_problem.find("unknown_key"), std::string::npos) << site.layout_problem;
  EXPECT_EQ(site.layout->reaches.size(), 1U) << "the last good layout is kept";

  // --config: the same from a file, for the site its [lcm] channel_prefix names.
  DashboardStore from_file;
  EXPECT_EQ(from_file.SetLayout(
                daemon::ParseDaemonConfig(ShippedConfigText("canalidd-asce2.toml"), "asce2.toml"),
                "asce2.toml"),
            "CANALID_ASCE2_");
  EXPECT_EQ(from_file.sites().at("CANALID_ASCE2_").layout->source, "asce2.toml");
}

TEST(DashboardStore, SitesAndSeriesBeyondTheLimitsAreRefused) {
  StoreLimits limits;
  limits.max_sites = 2;
  limits.max_series = 4;
  DashboardStore store(limits);
  EXPECT_EQ(store.OnMessage("A_SAMPLE_p", Encoded(MakeSample(1))), Ingest::kUsed);   // 3 series
  EXPECT_EQ(store.OnMessage("B_MODEL_pool2", Encoded(MakeModel())), Ingest::kUsed);  // 1 of 2
  EXPECT_EQ(store.OnMessage("C_HEALTH", Encoded(MakeHealth())), Ingest::kRefused);
  EXPECT_EQ(store.series().size(), 4U);
  EXPECT_EQ(store.counters().series_refused, 1);
  EXPECT_EQ(store.counters().refused, 1);
  // The refused parameter still has its latest value; it only has no history.
  const ModelTrack& track = store.sites().at("B_").reaches.at("pool2").models.begin()->second;
  EXPECT_EQ(track.params.at("area_m2"), nullptr);
  EXPECT_DOUBLE_EQ(track.latest.param_values[1], 6000.0);
}

// The ring against a plain deque doing the same by brute force.
TEST(SeriesRing, KeepsTheNewestPointsWithinItsCountAndAge) {
  std::mt19937 random(7);
  for (const std::size_t capacity : {1U, 5U, 64U}) {
    for (const double window : {3.0, 50.0, 1e9}) {
      SeriesRing ring(capacity, window);
      std::deque<SeriesPoint> reference;
      double t = 0.0;
      for (int i = 0; i < 2000; ++i) {
        t += std::uniform_real_distribution<double>(0.0, i % 300 < 150 ? 0.5 : 5.0)(random);
        const SeriesPoint p{t, static_cast<float>(i), NAN};
        ring.Append(p);
        reference.push_back(p);
        if (reference.size() > capacity) reference.pop_front();
        while (reference.size() > 1 && reference.front().t < t - window) reference.pop_front();
        ASSERT_EQ(ring.size(), reference.size()) << capacity << " " << window << " " << i;
        for (std::size_t k = 0; k < reference.size(); ++k) {
          ASSERT_EQ(ring.at(k).value, reference[k].value) << capacity << " " << window << " " << i;
        }
        EXPECT_EQ(ring.appended(), i + 1);
        EXPECT_EQ(ring.first_sequence(), i + 1 - static_cast<int>(reference.size()));
      }
    }
  }
}

TEST(DashboardJson, DeltasCarryOnlyTheNewPointsAndSnapshotsAreThinned) {
  DashboardStore store;
  for (int i = 1; i <= 100; ++i) store.OnMessage("S_SAMPLE_p", Encoded(MakeSample(i)));
  const int level = store.sites().at("S_").sources.at("p").channels.at("level_m").series->id;
  DeltaWriter writer;
  const auto first = nlohmann::json::parse(writer.Next(store, 0, 100000));
  EXPECT_EQ(first["type"], "delta");
  EXPECT_EQ(first["points"][std::to_string(level)].size(), 100U);
  const auto second = nlohmann::json::parse(writer.Next(store, 0, 100000));
  EXPECT_FALSE(second["points"].contains(std::to_string(level)));
  store.OnMessage("S_SAMPLE_p", Encoded(MakeSample(101)));
  const auto third = nlohmann::json::parse(writer.Next(store, 0, 100000));
  ASSERT_EQ(third["points"][std::to_string(level)].size(), 1U);
  EXPECT_DOUBLE_EQ(third["points"][std::to_string(level)][0][0].get<double>(),
                   static_cast<double>(MakeSample(101).utime) * 1e-6);
  EXPECT_EQ(third["state"]["sites"][0]["sources"][0]["sequence"], 101);

  // A burst is thinned like a snapshot, the newest point kept.
  for (int i = 102; i <= 400; ++i) store.OnMessage("S_SAMPLE_p", Encoded(MakeSample(i)));
  const auto burst = nlohmann::json::parse(writer.Next(store, 0, 10));
  const auto& burst_points = burst["points"][std::to_string(level)];
  EXPECT_LE(burst_points.size(), 10U);
  EXPECT_DOUBLE_EQ(burst_points.back()[0].get<double>(),
                   static_cast<double>(MakeSample(400).utime) * 1e-6);

  const auto snapshot = nlohmann::json::parse(SnapshotJson(store, 0, 10));
  const auto& thinned = snapshot["points"][std::to_string(level)];
  EXPECT_LE(thinned.size(), 10U);
  EXPECT_GE(thinned.size(), 9U);
  EXPECT_DOUBLE_EQ(thinned.back()[0].get<double>(),
                   static_cast<double>(MakeSample(400).utime) * 1e-6)
      << "the newest point is always sent";
}

// /metrics read by the reference parser: the health counters are the HEALTH message's, the
// model's parameters and the message counters are there, and label values with quotes,
// backslashes and newlines survive.
TEST(DashboardMetrics, TheReferenceParserReadsWhatTheMessagesSaid) {
  const auto dir = canalid::testing::TestDirectory("dashboard_metrics_parse");
  DashboardStore store;
  canalid::health_t health = MakeHealth();
  health.component = "plc.\"odd\\name\n\xff";  // quotes, backslash, newline, not UTF-8
  store.OnMessage("S_HEALTH", Encoded(health));
  store.OnMessage("S_MODEL_pool2", Encoded(MakeModel()));
  store.OnMessage("S_SAMPLE_plc", Encoded(MakeSample(3)));
  store.OnMessage("S_EXPERIMENT_pool2", Encoded(MakeExperiment()));
  store.OnMessage("S_SAMPLE_plc", std::vector<std::uint8_t>(10, 0xAB));
  drivers::HttpServerStats server;
  server.websocket_dropped_slow = 3;
  const auto samples = ParsedMetrics(MetricsText(store, server, 1763700001000000), dir);
  const std::string shown = "plc.\"odd\\name\n\xEF\xBF\xBD";  // the invalid byte as U+FFFD
  ASSERT_FALSE(samples.empty());
  for (std::size_t i = 0; i < health.counter_names.size(); ++i) {
    EXPECT_EQ(
        MetricValue(samples, "canalid_health_counter_total",
                    {{"site", "S_"}, {"component", shown}, {"name", health.counter_names[i]}}),
        static_cast<double>(health.counter_values[i]))
        << health.counter_names[i];
  }
  for (std::size_t i = 0; i < health.gauge_names.size(); ++i) {
    const double value = MetricValue(samples, "canalid_health_gauge",
                                     {{"component", shown}, {"name", health.gauge_names[i]}});
    if (std::isnan(health.gauge_values[i])) {
      EXPECT_TRUE(std::isnan(value));
    } else {
      EXPECT_DOUBLE_EQ(value, health.gauge_values[i]) << health.gauge_names[i];
    }
  }
  EXPECT_DOUBLE_EQ(MetricValue(samples, "canalid_model_param",
                               {{"reach", "pool2"}, {"kind", "id"}, {"param", "delay_s"}}),
                   540.0);
  EXPECT_DOUBLE_EQ(MetricValue(samples, "canalid_model_param_std", {{"param", "delay_s"}}), 12.5);
  EXPECT_TRUE(std::isnan(MetricValue(samples, "canalid_model_param_std", {{"param", "area_m2"}})));
  EXPECT_DOUBLE_EQ(MetricValue(samples, "canalid_channel_value", {{"channel", "level_m"}}), 1.234);
  EXPECT_DOUBLE_EQ(MetricValue(samples, "canalid_experiment_step", {{"reach", "pool2"}}),
                   MakeExperiment().step);
  EXPECT_DOUBLE_EQ(
      MetricValue(samples, "canalid_dashboard_messages_total", {{"result", "malformed"}}), 1.0);
  EXPECT_DOUBLE_EQ(
      MetricValue(samples, "canalid_dashboard_http_total", {{"event", "websocket_dropped_slow"}}),
      3.0);
  EXPECT_DOUBLE_EQ(MetricValue(samples, "canalid_model_age_seconds", {{"kind", "id"}}),
                   static_cast<double>(1763700001000000 - MakeModel().utime) * 1e-6);
}

}  // namespace
}  // namespace canalid::dashboard
