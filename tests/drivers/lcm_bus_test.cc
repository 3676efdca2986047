// The Bus contract, checked on LcmBus over memq:// and on FakeBus alike, so code tested against
// the fake behaves the same on LCM.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/lcm/bus.h"
#include "drivers/lcm/fake_bus.h"
#include "drivers/lcm/lcm_bus.h"
#include "drivers/modbus/plc_poller.h"
#include "lcm_test_messages.h"

namespace canalid::drivers {
namespace {

// sample_t's status and quality codes are the driver's enums, so the daemon converts by cast.
static_assert(static_cast<int>(PlcErrorKind::kNone) == canalid::sample_t::STATUS_OK);
static_assert(static_cast<int>(PlcErrorKind::kTimeout) == canalid::sample_t::STATUS_TIMEOUT);
static_assert(static_cast<int>(PlcErrorKind::kException) == canalid::sample_t::STATUS_EXCEPTION);
static_assert(static_cast<int>(PlcErrorKind::kDisconnected) ==
              canalid::sample_t::STATUS_DISCONNECTED);
static_assert(static_cast<int>(PlcErrorKind::kBadData) == canalid::sample_t::STATUS_BAD_DATA);
static_assert(static_cast<int>(PlcErrorKind::kConfig) == canalid::sample_t::STATUS_CONFIG);
static_assert(static_cast<int>(SampleQuality::kValid) == canalid::sample_t::QUALITY_VALID);
static_assert(static_cast<int>(SampleQuality::kReadFailed) ==
              canalid::sample_t::QUALITY_READ_FAILED);
static_assert(static_cast<int>(SampleQuality::kOutOfRange) ==
              canalid::sample_t::QUALITY_OUT_OF_RANGE);
static_assert(static_cast<int>(SampleQuality::kNotFinite) == canalid::sample_t::QUALITY_NOT_FINITE);

using BusFactory = std::function<std::unique_ptr<Bus>()>;

struct BusKind {
  const char* name;
  BusFactory make;
};
void PrintTo(const BusKind& kind, std::ostream* os) { *os << kind.name; }

class BusContract : public ::testing::TestWithParam<BusKind> {
 protected:
  std::unique_ptr<Bus> bus_ = GetParam().make();
  std::vector<uint8_t> buffer_;
};

TEST_P(BusContract, TypedRoundTripOfEveryMessageType) {
  std::vector<canalid::sample_t> samples;
  canalid::model_snapshot_t model;
  canalid::experiment_state_t experiment;
  canalid::health_t health;
  canalid::config_t config;
  canalid::command_t command;
  int received = 0;
  auto keep = [&received](auto& into) {
    return [&into, &received](const std::string&, const auto& m) {
      into = m;
      ++received;
    };
  };
  SubscribeMessage<canalid::sample_t>(*bus_, "CANALID_SAMPLE_.*",
                                      [&](const std::string& channel, const canalid::sample_t& m) {
                                        EXPECT_EQ(channel, "CANALID_SAMPLE_pool2");
                                        samples.push_back(m);
                                        ++received;
                                      });
  SubscribeMessage<canalid::model_snapshot_t>(*bus_, "CANALID_MODEL", keep(model));
  SubscribeMessage<canalid::experiment_state_t>(*bus_, "CANALID_EXPERIMENT", keep(experiment));
  SubscribeMessage<canalid::health_t>(*bus_, "CANALID_HEALTH", keep(health));
  SubscribeMessage<canalid::config_t>(*bus_, "CANALID_CONFIG", keep(config));
  SubscribeMessage<canalid::command_t>(*bus_, "CANALID_COMMAND", keep(command));

  for (int64_t i = 0; i < 50; ++i) {
    ASSERT_TRUE(PublishMessage(*bus_, "CANALID_SAMPLE_pool2", testing::MakeSample(i), buffer_));
  }
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_MODEL", testing::MakeModel(), buffer_));
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_EXPERIMENT", testing::MakeExperiment(), buffer_));
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_HEALTH", testing::MakeHealth(), buffer_));
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_CONFIG", testing::MakeConfig(), buffer_));
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_COMMAND", testing::MakeCommand(), buffer_));
  // Not matched by any subscription (regexes match the whole channel name).
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_MODEL_OTHER", testing::MakeModel(), buffer_));

  while (received < 55) {
    const int n = bus_->Handle(5.0);
    ASSERT_GT(n, 0) << "messages lost: " << received << " of 55 received";
  }
  EXPECT_EQ(bus_->Handle(0.0), 0) << "the unmatched channel reaches no handler";
  ASSERT_EQ(samples.size(), 50u);
  for (int64_t i = 0; i < 50; ++i)
    testing::ExpectEqual(testing::MakeSample(i), samples[static_cast<std::size_t>(i)]);
  testing::ExpectEqual(testing::MakeModel(), model);
  testing::ExpectEqual(testing::MakeExperiment(), experiment);
  testing::ExpectEqual(testing::MakeHealth(), health);
  testing::ExpectEqual(testing::MakeConfig(), config);
  testing::ExpectEqual(testing::MakeCommand(), command);
  EXPECT_EQ(bus_->handler_failures(), 0);
}

TEST_P(BusContract, HandlerExceptionsAndUndecodableMessagesAreCountedNotThrown) {
  int good = 0;
  SubscribeMessage<canalid::health_t>(
      *bus_, "CANALID_HEALTH", [&](const std::string&, const canalid::health_t&) { ++good; });
  bus_->Subscribe("THROWS", [](const std::string&, std::span<const uint8_t>) -> bool {
    throw std::runtime_error("handler bug");
  });
  const std::vector<uint8_t> garbage = {1, 2, 3};
  ASSERT_TRUE(bus_->Publish("CANALID_HEALTH", garbage));
  ASSERT_TRUE(bus_->Publish("THROWS", garbage));
  ASSERT_TRUE(PublishMessage(*bus_, "CANALID_HEALTH", testing::MakeHealth(), buffer_));
  int handled = 0;
  while (handled < 3) {
    int n = 0;
    EXPECT_NO_THROW(n = bus_->Handle(5.0));
    ASSERT_GT(n, 0);
    handled += n;
  }
  EXPECT_EQ(good, 1);
  EXPECT_EQ(bus_->handler_failures(), 2);
}

TEST_P(BusContract, UnsubscribeStopsDelivery) {
  int count = 0;
  const int id = bus_->Subscribe("A", [&](const std::string&, std::span<const uint8_t>) {
    ++count;
    return true;
  });
  const std::vector<uint8_t> data = {9};
  bus_->Publish("A", data);
  while (count == 0) ASSERT_GT(bus_->Handle(5.0), 0);
  bus_->Unsubscribe(id);
  bus_->Publish("A", data);
  bus_->Handle(0.0);
  EXPECT_EQ(count, 1);
}

INSTANTIATE_TEST_SUITE_P(
    Buses, BusContract,
    ::testing::Values(BusKind{"memq", [] { return std::make_unique<LcmBus>("memq://"); }},
                      BusKind{"fake", [] { return std::make_unique<FakeBus>(); }}),
    [](const ::testing::TestParamInfo<BusKind>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(LcmBus, EmptyUrlUsesLcmDefaultUrl) {
  // The environment variable is how operators redirect the daemon without editing its config.
  // setenv is not thread-safe; here it runs before any thread of the test reads the environment.
  ASSERT_EQ(setenv("LCM_DEFAULT_URL", "memq://", 1), 0);  // NOLINT(concurrency-mt-unsafe)
  LcmBus bus("");
  unsetenv("LCM_DEFAULT_URL");  // NOLINT(concurrency-mt-unsafe)
  int count = 0;
  bus.Subscribe("X", [&](const std::string&, std::span<const uint8_t> d) {
    count += static_cast<int>(d.size());
    return true;
  });
  const std::vector<uint8_t> data = {1, 2, 3, 4};
  ASSERT_TRUE(bus.Publish("X", data));
  ASSERT_EQ(bus.Handle(5.0), 1);
  EXPECT_EQ(count, 4);
}

TEST(LcmBus, BadUrlThrowsNamingIt) {
  try {
    LcmBus bus("nosuchprovider://x");
    FAIL() << "no throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos) << e.what();
  }
}

TEST(FakeBus, RecordsPublishesAndHonoursQueueCapacity) {
  FakeBus bus;
  int count = 0;
  bus.Subscribe(
      "B",
      [&](const std::string&, std::span<const uint8_t>) {
        ++count;
        return true;
      },
      2);
  const std::vector<uint8_t> data = {7};
  for (int i = 0; i < 5; ++i) bus.Publish("B", data);
  EXPECT_EQ(bus.Handle(0.0), 2);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(bus.dropped(), 3);
  ASSERT_EQ(bus.published().size(), 5u);
  EXPECT_EQ(bus.published()[4].channel, "B");
  bus.set_publish_fails(true);
  EXPECT_FALSE(bus.Publish("B", data));
}

}  // namespace
}  // namespace canalid::drivers
