// An LCM log written through LcmBus with file://...?mode=w is read back two independent ways:
// lcm::LogFile event by event, and LcmBus over file://...?speed=0 (the lossless in-process replay
// the replay command uses). Every canalid type must decode to what was published.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "drivers/lcm/lcm_bus.h"
#include "lcm_test_messages.h"

namespace canalid::drivers {
namespace {

std::filesystem::path FreshLog(const std::string& name) {
  const auto dir = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / "lcm_log";
  std::filesystem::create_directories(dir);
  auto path = dir / name;
  std::filesystem::remove(path);
  return path;
}

void WriteLog(const std::filesystem::path& path) {
  LcmBus bus("file://" + path.string() + "?mode=w");
  std::vector<uint8_t> buffer;
  for (int64_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(PublishMessage(bus, "CANALID_SAMPLE_pool2", testing::MakeSample(i), buffer));
  }
  ASSERT_TRUE(PublishMessage(bus, "CANALID_MODEL_pool2", testing::MakeModel(), buffer));
  ASSERT_TRUE(PublishMessage(bus, "CANALID_EXPERIMENT_pool2", testing::MakeExperiment(), buffer));
  ASSERT_TRUE(PublishMessage(bus, "CANALID_HEALTH", testing::MakeHealth(), buffer));
  ASSERT_TRUE(PublishMessage(bus, "CANALID_CONFIG", testing::MakeConfig(), buffer));
  ASSERT_TRUE(PublishMessage(bus, "CANALID_COMMAND", testing::MakeCommand(), buffer));
}  // the bus closes the log here

template <class Message>
Message Decode(const lcm::LogEvent& event) {
  Message m;
  EXPECT_EQ(m.decode(event.data, 0, event.datalen), event.datalen) << event.channel;
  return m;
}

TEST(LcmLog, LogFileReadsBackEveryType) {
  const auto path = FreshLog("every-type.lcmlog");
  WriteLog(path);
  lcm::LogFile log(path.string(), "r");
  ASSERT_TRUE(log.good());
  std::vector<std::string> channels;
  int64_t sample_index = 0;
  int64_t last_timestamp = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    channels.push_back(e->channel);
    EXPECT_GE(e->timestamp, last_timestamp);
    last_timestamp = e->timestamp;
    if (e->channel == "CANALID_SAMPLE_pool2") {
      testing::ExpectEqual(testing::MakeSample(sample_index++), Decode<canalid::sample_t>(*e));
    } else if (e->channel == "CANALID_MODEL_pool2") {
      testing::ExpectEqual(testing::MakeModel(), Decode<canalid::model_snapshot_t>(*e));
    } else if (e->channel == "CANALID_EXPERIMENT_pool2") {
      testing::ExpectEqual(testing::MakeExperiment(), Decode<canalid::experiment_state_t>(*e));
    } else if (e->channel == "CANALID_HEALTH") {
      testing::ExpectEqual(testing::MakeHealth(), Decode<canalid::health_t>(*e));
    } else if (e->channel == "CANALID_CONFIG") {
      testing::ExpectEqual(testing::MakeConfig(), Decode<canalid::config_t>(*e));
    } else if (e->channel == "CANALID_COMMAND") {
      testing::ExpectEqual(testing::MakeCommand(), Decode<canalid::command_t>(*e));
    }
  }
  const std::vector<std::string> expected = {"CANALID_SAMPLE_pool2",     "CANALID_SAMPLE_pool2",
                                             "CANALID_SAMPLE_pool2",     "CANALID_MODEL_pool2",
                                             "CANALID_EXPERIMENT_pool2", "CANALID_HEALTH",
                                             "CANALID_CONFIG",           "CANALID_COMMAND"};
  EXPECT_EQ(channels, expected);
}

TEST(LcmLog, FileUrlReplaysTheLogThroughTheBus) {
  const auto path = FreshLog("replay.lcmlog");
  WriteLog(path);
  LcmBus bus("file://" + path.string() + "?speed=0");
  std::vector<canalid::sample_t> samples;
  std::map<std::string, int> seen;
  SubscribeMessage<canalid::sample_t>(
      bus, "CANALID_SAMPLE_.*",
      [&](const std::string&, const canalid::sample_t& m) { samples.push_back(m); });
  SubscribeMessage<canalid::command_t>(
      bus, "CANALID_COMMAND", [&](const std::string& channel, const canalid::command_t& m) {
        testing::ExpectEqual(testing::MakeCommand(), m);
        ++seen[channel];
      });
  // Bounded: the log holds 8 events; each Handle dispatches at least one or times out.
  for (int round = 0; round < 100 && seen["CANALID_COMMAND"] == 0; ++round) {
    if (bus.Handle(2.0) <= 0) break;
  }
  ASSERT_EQ(samples.size(), 3u);
  for (int64_t i = 0; i < 3; ++i)
    testing::ExpectEqual(testing::MakeSample(i), samples[static_cast<std::size_t>(i)]);
  EXPECT_EQ(seen["CANALID_COMMAND"], 1);
  EXPECT_EQ(bus.handler_failures(), 0);
}

}  // namespace
}  // namespace canalid::drivers
