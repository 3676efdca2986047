// Writes the seed inputs of the LCM fuzz targets, encoded by the project's own message types
// (the fully populated messages of tests/drivers/lcm_test_messages.h):
//   lcm_seeds COMMAND_DIR LOG_DIR DAEMON_CONFIG_TOML
// COMMAND_DIR gets canalid.command_t messages signed with the key of lcm_fuzz_key.h (accepted,
// each kind, unknown kind, stale, bad MAC, empty sender); LOG_DIR gets LCM logs written by
// liblcm's own writer (lcm::LogFile): a daemon's CONFIG (the TOML file's text), samples, an
// experiment state and a model, one with another daemon's messages first, and a truncated one.
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/auth/command_auth.h"
#include "drivers/lcm/command_sender.h"
#include "tests/drivers/lcm_test_messages.h"
#include "tests/fuzz/lcm_fuzz_key.h"

namespace {

template <class Message>
std::vector<uint8_t> Encode(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  if (message.encode(bytes.data(), 0, static_cast<int>(bytes.size())) !=
      static_cast<int>(bytes.size()))
    throw std::runtime_error("lcm encode failed");
  return bytes;
}

void WriteFile(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
}

canalid::command_t Signed(const canalid::command_t& m) {
  return canalid::drivers::BuildSignedCommand(
      canalid::fuzz::kCommandKey,
      canalid::drivers::CommandFieldsOf(m, canalid::fuzz::kCommandChannel));
}

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
};

void WriteLog(const std::filesystem::path& path, const std::vector<Event>& events) {
  lcm::LogFile log(path.string(), "w");
  if (!log.good()) throw std::runtime_error(path.string() + ": cannot create the log");
  int64_t utime = 1763700000000000;
  for (const Event& e : events) {
    lcm::LogEvent event{};
    event.timestamp = utime += 1000;
    event.channel = e.channel;
    event.datalen = static_cast<int32_t>(e.data.size());
    event.data = const_cast<uint8_t*>(e.data.data());
    if (log.writeEvent(&event) != 0) throw std::runtime_error(path.string() + ": write failed");
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s COMMAND_DIR LOG_DIR DAEMON_CONFIG_TOML\n", argv[0]);
    return 2;
  }
  try {
    const std::filesystem::path commands = argv[1];
    const std::filesystem::path logs = argv[2];
    std::filesystem::create_directories(commands);
    std::filesystem::create_directories(logs);

    canalid::command_t base = canalid::testing::MakeCommand();
    base.utime = canalid::fuzz::kNowUs;
    WriteFile(commands / "seed-accepted", Encode(Signed(base)));
    WriteFile(commands / "seed-bad-mac", Encode(canalid::testing::MakeCommand()));
    for (int8_t kind : {int8_t{2}, int8_t{3}, int8_t{4}, int8_t{9}}) {
      canalid::command_t m = base;
      m.kind = kind;
      m.argument = kind == 2 ? "" : m.argument;
      WriteFile(commands / ("seed-kind-" + std::to_string(kind)), Encode(Signed(m)));
    }
    canalid::command_t stale = base;
    stale.utime -= 60'000'000;
    WriteFile(commands / "seed-stale", Encode(Signed(stale)));
    canalid::command_t anonymous = base;
    anonymous.sender.clear();
    WriteFile(commands / "seed-empty-sender", Encode(Signed(anonymous)));

    std::ifstream toml(argv[3]);
    std::ostringstream text;
    text << toml.rdbuf();
    if (!toml) throw std::runtime_error(std::string(argv[3]) + ": cannot read");
    canalid::config_t config = canalid::testing::MakeConfig();
    config.text = text.str();
    const std::vector<Event> daemon = {
        {"CANALID_CONFIG", Encode(config)},
        {"CANALID_SAMPLE_plc1", Encode(canalid::testing::MakeSample(0))},
        {"CANALID_SAMPLE_plc1", Encode(canalid::testing::MakeSample(1))},
        {"CANALID_EXPERIMENT_pool2", Encode(canalid::testing::MakeExperiment())},
        {"CANALID_MODEL_pool2", Encode(canalid::testing::MakeModel())},
        {"CANALID_HEALTH", Encode(canalid::testing::MakeHealth())},
    };
    WriteLog(logs / "seed-daemon.lcmlog", daemon);
    std::vector<Event> mixed = {{"OTHER_SAMPLE_plc9", Encode(canalid::testing::MakeSample(7))},
                                {"UNRELATED", {1, 2, 3}}};
    mixed.insert(mixed.end(), daemon.begin(), daemon.end());
    mixed.push_back({"OTHER_CONFIG", Encode(config)});
    WriteLog(logs / "seed-two-daemons.lcmlog", mixed);
    WriteLog(logs / "seed-truncated.lcmlog", daemon);
    std::filesystem::resize_file(logs / "seed-truncated.lcmlog",
                                 std::filesystem::file_size(logs / "seed-truncated.lcmlog") - 7);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lcm_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
