// lcm-logger (Debian's liblcm-bin) records what LcmBus publishes on udpm, so operators can log
// the daemon with the stock tool and replay the file.  udpm needs a multicast route: the test runs
// itself again in a private network namespace whose loopback has one (the host's routes are never
// touched), and fails with the reason where no such namespace can be made.
#include <signal.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "drivers/lcm/lcm_bus.h"
#include "lcm_test_messages.h"
#include "tests/support/private_network.h"

namespace canalid::drivers {
namespace {

bool HasMulticastRoute() {
  FILE* pipe = popen("ip route show 2>/dev/null", "r");
  if (pipe == nullptr) return false;
  std::string text;
  std::array<char, 256> chunk{};
  while (fgets(chunk.data(), static_cast<int>(chunk.size()), pipe) != nullptr) text += chunk.data();
  pclose(pipe);
  return text.find("224.0.0.0/4") != std::string::npos;
}

/// The events of `path` on `channel` so far (the logger may be writing it; a partial last event
/// just ends the read).
std::vector<std::vector<uint8_t>> Events(const std::filesystem::path& path,
                                         const std::string& channel) {
  std::vector<std::vector<uint8_t>> out;
  if (!std::filesystem::exists(path)) return out;
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) return out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == channel) {
      const auto* bytes = static_cast<const uint8_t*>(e->data);
      out.emplace_back(bytes, bytes + e->datalen);
    }
  }
  return out;
}

TEST(LcmLogger, RecordsASamplePublishedOnUdpm) {
  constexpr const char* kInside = "CANALID_LCM_LOGGER_TEST_IN_PRIVATE_NETWORK";
  if (std::getenv(kInside) == nullptr) {  // NOLINT(concurrency-mt-unsafe): one thread here
    const auto scratch = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / "lcm_logger";
    std::filesystem::create_directories(scratch);
    const std::string problem = canalid::testing::PrivateNetworkProblem(scratch);
    ASSERT_TRUE(problem.empty()) << problem;
    std::vector<std::string> argv = canalid::testing::InNewPrivateNetwork();
    argv.push_back(std::filesystem::read_symlink("/proc/self/exe").string());
    argv.emplace_back("--gtest_filter=LcmLogger.RecordsASamplePublishedOnUdpm");
    canalid::testing::ChildProcess inside(argv, {std::string(kInside) + "=1"},
                                          scratch / "private-network-run.log");
    EXPECT_EQ(inside.WaitExit(60000), 0) << inside.output();
    return;
  }
  ASSERT_TRUE(HasMulticastRoute()) << "no 224.0.0.0/4 route inside the private network";
  // A private port so concurrent runs and real daemons on the default group do not mix in.
  std::mt19937 rng(static_cast<unsigned>(getpid()));
  const int port = 20000 + static_cast<int>(rng() % 20000);
  const std::string url = "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
  const auto dir = std::filesystem::path(CANALID_BINARY_DIR) / "test-output" / "lcm_logger";
  std::filesystem::create_directories(dir);
  const auto log_path = dir / ("logger-" + std::to_string(port) + ".lcmlog");
  std::filesystem::remove(log_path);

  canalid::testing::ChildOptions options;
  options.argv = {"lcm-logger", "-f", "--flush-interval=10", "--lcm-url=" + url, log_path.string()};
  options.log_path = dir / ("logger-" + std::to_string(port) + ".out");
  canalid::testing::ChildProcess logger(options);

  LcmBus bus(url);
  std::vector<uint8_t> buffer;
  // The logger is ready once a probe published here shows up in its file: a bounded wait (30 s)
  // that publishes and re-checks every 50 ms and ends at once if the logger exits (a later probe
  // is what makes the logger flush an earlier one).
  bool publish_failed = false;
  const bool ready = logger.WaitUntil(
      [&] {
        publish_failed =
            publish_failed || !PublishMessage(bus, "CANALID_PROBE", testing::MakeHealth(), buffer);
        return !Events(log_path, "CANALID_PROBE").empty();
      },
      30000, 50);
  ASSERT_FALSE(publish_failed);
  ASSERT_TRUE(ready) << "lcm-logger did not record a probe within 30 s: " << logger.output();

  const canalid::sample_t sent = testing::MakeSample(7);
  ASSERT_TRUE(PublishMessage(bus, "CANALID_SAMPLE_pool2", sent, buffer));
  // lcm-logger flushes its file only when a message arrives --flush-interval after the last
  // flush: probes keep coming until the sample is in the file, whatever the timing.
  std::vector<std::vector<uint8_t>> recorded;
  logger.WaitUntil(
      [&] {
        recorded = Events(log_path, "CANALID_SAMPLE_pool2");
        if (!recorded.empty()) return true;
        publish_failed =
            publish_failed || !PublishMessage(bus, "CANALID_PROBE", testing::MakeHealth(), buffer);
        return false;
      },
      30000, 20);
  EXPECT_FALSE(publish_failed);
  EXPECT_EQ(logger.Stop(SIGINT), 0) << logger.output();

  ASSERT_EQ(recorded.size(), 1u);
  canalid::sample_t got;
  ASSERT_EQ(got.decode(recorded[0].data(), 0, static_cast<int>(recorded[0].size())),
            static_cast<int>(recorded[0].size()));
  testing::ExpectEqual(sent, got);
}

}  // namespace
}  // namespace canalid::drivers
