// Replay throughput: an LCM log of canalidd (config/canalidd-asce2.toml: one reach, online ID bank
// over 24 delays, the designed on_start experiment and its batch identification) read in process
// and run through the daemon's per-reach code (ReplaySession), as `canalid replay` does.  The log
// holds `samples` polls of 6 channels whose flows and level follow canalsim's PRBS record of pool 2
// (tests/data/sim), repeated.  Reported: samples per second through the whole path (read, decode,
// pipeline), the same without the online bank, and the read-and-decode part alone.
#include <benchmark/benchmark.h>
#include <lcm/lcm-cpp.hpp>

#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/canalid/replay_session.h"
#include "daemon/config/config_loader.h"
#include "drivers/lcm/log_messages.h"

namespace {

namespace fs = std::filesystem;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

template <class Message>
void Write(lcm::LogFile& log, std::int64_t number, const std::string& channel, const Message& m,
           std::vector<std::uint8_t>& buffer) {
  buffer.resize(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  lcm::LogEvent e;
  e.eventnum = number;
  e.timestamp = m.utime;
  e.channel = channel;
  e.datalen = static_cast<std::int32_t>(buffer.size());
  e.data = buffer.data();
  log.writeEvent(&e);
}

// The log of `samples` polls, written once per size into the build tree.
std::string MakeLog(std::int64_t samples) {
  const fs::path path =
      fs::path(CANALID_BENCH_BINARY_DIR) / ("replay-bench-" + std::to_string(samples) + ".lcmlog");
  if (fs::exists(path)) return path.string();
  std::vector<std::array<double, 3>> rows;
  std::istringstream csv(
      ReadText(std::string(CANALID_BENCH_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv"));
  std::string line;
  std::getline(csv, line);
  while (std::getline(csv, line)) {
    std::array<double, 4> v{};
    std::istringstream s(line);
    for (double& x : v) {
      std::getline(s, line, ',');
      x = std::stod(line);
    }
    rows.push_back({v[1], v[2], v[3]});
  }
  {
    lcm::LogFile log(path.string() + ".part", "w");
    std::vector<std::uint8_t> buffer;
    canalid::config_t config;
    config.utime = 1;
    config.path = "config/canalidd-asce2.toml";
    config.text = ReadText(std::string(CANALID_BENCH_SOURCE_DIR) + "/config/canalidd-asce2.toml");
    Write(log, 0, "CANALID_ASCE2_CONFIG", config, buffer);
    // Every field set, as the daemon's poller sets them (lcm-gen leaves the scalars
    // uninitialised): a good poll, so the configuration's designed experiment runs.
    canalid::sample_t s{};
    s.status = canalid::sample_t::STATUS_OK;
    s.exception_code = 0;
    s.round_trip_s = 0.004F;
    s.source = "asce2";
    s.channel_names = {"heartbeat",   "pool2_inflow",   "pool2_outflow",
                       "pool2_level", "gate1_position", "gate1_setpoint"};
    s.num_channels = 6;
    s.quality.assign(6, 0);
    for (std::int64_t k = 0; k < samples; ++k) {
      const auto& r = rows[static_cast<std::size_t>(k) % rows.size()];
      s.utime = 2 + k * 100000;
      s.sequence = k;
      s.values = {0.0, r[0], r[1], r[2], 1.5, 1.5};
      Write(log, k + 1, "CANALID_ASCE2_SAMPLE_asce2", s, buffer);
    }
  }  // closes the log
  fs::rename(path.string() + ".part", path);
  return path.string();
}

// range(1): the online bank's longest delay, s (the config's is 1400 s: 24 delays of 60 s);
// another value replays with the config changed to it (--config); 0 replays without the online
// bank (`online_models = []`): the rest of the replay, what the bank's cost is compared with.
void BM_ReplayThroughput(benchmark::State& state) {
  const std::string log = MakeLog(state.range(0));
  std::optional<canalid::config::DaemonConfig> config;
  if (state.range(1) != 1400) {
    std::string text =
        ReadText(std::string(CANALID_BENCH_SOURCE_DIR) + "/config/canalidd-asce2.toml");
    const std::string key =
        state.range(1) == 0 ? "online_models = [\"id\"]" : "max_delay_s = 1400.0";
    const std::string value = state.range(1) == 0
                                  ? std::string("online_models = []")
                                  : "max_delay_s = " + std::to_string(state.range(1));
    const std::size_t at = text.find(key);
    if (at == std::string::npos) {
      state.SkipWithError(("config/canalidd-asce2.toml has no `" + key + "`").c_str());
      return;
    }
    text.replace(at, key.size(), value);
    config = canalid::daemon::ParseDaemonConfig(text, "bench");
  }
  std::int64_t samples = 0;
  for (auto _ : state) {
    canalid::cli::ReplaySessionOptions options;
    options.log_path = log;
    options.config = config;
    canalid::cli::ReplaySession session(
        options, [](const canalid::cli::ReplayModel&) {}, [](const std::string&) {});
    const canalid::drivers::LogScanResult result =
        canalid::drivers::ScanCanalidLog(log, {}, session);
    samples += result.samples;
    benchmark::DoNotOptimize(session.FinalModels());
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReplayThroughput)
    ->Args({200000, 1400})
    ->Args({200000, 600})
    ->Args({200000, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Reading and decoding alone (a visitor that does nothing).
void BM_ReadAndDecode(benchmark::State& state) {
  const std::string log = MakeLog(state.range(0));
  std::int64_t samples = 0;
  for (auto _ : state) {
    canalid::drivers::LogMessageVisitor nothing;
    samples += canalid::drivers::ScanCanalidLog(log, {}, nothing).samples;
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadAndDecode)->Arg(200000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
