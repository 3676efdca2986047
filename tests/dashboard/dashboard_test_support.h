#pragma once
// Helpers of the dashboard suites: LCM messages as bytes, logs written by LCM's own writer, the
// shipped configurations, and /metrics text read back through Python's reference Prometheus
// parser (parse_metrics.py).
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_program.h"

namespace canalid::testing {

/// `message` encoded as lcm-gen encodes it.
template <class Message>
std::vector<std::uint8_t> Encoded(const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// An LCM log written by LCM's own writer (lcm::LogFile), the format lcm-logger writes.
class TestLog {
 public:
  explicit TestLog(const std::filesystem::path& path) : log_(path.string(), "w") {
    EXPECT_TRUE(log_.good()) << path;
  }
  /// Appends `message` on `channel`, logged at `utime` (us since the epoch).
  template <class Message>
  void Write(const std::string& channel, const Message& message, std::int64_t utime) {
    const std::vector<std::uint8_t> bytes = Encoded(message);
    lcm::LogEvent event;
    event.eventnum = number_++;
    event.timestamp = utime;
    event.channel = channel;
    event.datalen = static_cast<std::int32_t>(bytes.size());
    event.data = const_cast<std::uint8_t*>(bytes.data());  // NOLINT: LCM's C-style event
    EXPECT_EQ(log_.writeEvent(&event), 0);
  }

 private:
  lcm::LogFile log_;
  std::int64_t number_ = 0;
};

/// The text of a shipped configuration, config/NAME.
inline std::string ShippedConfigText(const std::string& name) {
  return ReadFile(std::filesystem::path(CANALID_SOURCE_DIR) / "config" / name);
}

/// Every sample of `metrics` as the reference parser reads it ({"family", "type", "name",
/// "labels", "value"}); fails the test when the text does not parse.
inline std::vector<nlohmann::json> ParsedMetrics(const std::string& metrics,
                                                 const std::filesystem::path& dir) {
  const auto path = dir / "metrics.txt";
  WriteFile(path, metrics);
  const ProgramRun run = RunProgramWithin("/usr/bin/python3 " + std::string(CANALID_SOURCE_DIR) +
                                              "/tests/dashboard/parse_metrics.py " + path.string(),
                                          dir, 60);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  std::vector<nlohmann::json> samples;
  std::istringstream lines(run.out);
  for (std::string line; std::getline(lines, line);) samples.push_back(nlohmann::json::parse(line));
  return samples;
}

/// The value of the sample `name` whose labels include `labels`; fails the test when there is
/// none (and returns NaN), so a missing metric is never taken for a NaN one.
inline double MetricValue(const std::vector<nlohmann::json>& samples, const std::string& name,
                          const nlohmann::json& labels) {
  for (const auto& s : samples) {
    if (s["name"] != name) continue;
    bool all = true;
    for (const auto& [key, value] : labels.items()) {
      all = all && s["labels"].contains(key) && s["labels"][key] == value;
    }
    if (all) return s["value"].is_null() ? std::nan("") : s["value"].get<double>();
  }
  ADD_FAILURE() << "no metric " << name << " with labels " << labels.dump();
  return std::nan("");
}

}  // namespace canalid::testing
