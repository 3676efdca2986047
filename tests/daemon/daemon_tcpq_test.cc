// canalidd on a tcpq:// bus (the documented URL form) whose hub goes away: on main liblcm then
// selected on fd -1 and aborted the daemon. The truths: the daemon logs the loss, keeps running,
// reconnects with a backoff when the hub is back (subscribing its command channel again), and
// stops with exit 0. The hub is tests/support/tcpq_test_hub.h; the PLC is at 127.0.0.1:1, where
// nothing listens (the poller just keeps reconnecting), so no other process's PLC is written to.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <sstream>
#include <string>

#include "tests/support/child_process.h"
#include "tests/support/tcpq_test_hub.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;

// config/canalidd-asce2.toml with the bus, the PLC port, the state directory and commands set.
fs::path WriteConfig(const fs::path& dir, const std::string& url, const fs::path& key) {
  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/config/canalidd-asce2.toml");
  std::ostringstream out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("url = ", 0) == 0) line = "url = \"" + url + "\"";
    if (line.rfind("port = ", 0) == 0) line = "port = 1";
    if (line.rfind("state_directory = ", 0) == 0)
      line = "state_directory = \"" + (dir / "state").string() + "\"";
    if (line.rfind("enabled = false", 0) == 0)
      line = "enabled = true\nkey_file = \"" + key.string() + "\"";
    out << line << "\n";
  }
  const fs::path path = dir / "canalidd.toml";
  std::ofstream(path) << out.str();
  return path;
}

TEST(DaemonTcpq, LosingTheHubIsLoggedAndReconnectedNotAnAbort) {
  const fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "daemon_tcpq";
  fs::remove_all(dir);
  fs::create_directories(dir / "state");
  const fs::path key = dir / "command.key";
  std::ofstream(key) << std::string(64, 'a') << "\n";
  ::chmod(key.c_str(), 0600);
  TcpqTestHub hub;
  const fs::path config = WriteConfig(dir, hub.url(), key);

  auto first = std::async(std::launch::async, [&hub] { return hub.Accept(); });
  ChildProcess daemon(
      {std::string(CANALID_BINARY_DIR) + "/daemon/canalidd/canalidd", "--config", config.string()},
      {}, dir / "canalidd.log");
  const int hub_side = first.get();
  ASSERT_GE(hub_side, 0) << daemon.output();
  EXPECT_EQ(TcpqTestHub::ReadSubscribe(hub_side), "CANALID_ASCE2_COMMAND") << daemon.output();
  ASSERT_FALSE(daemon.WaitForLine("running:", kHubWaitMs).empty()) << daemon.output();

  // The hub goes away; it comes back (accepts again) once the daemon has noticed.
  const auto lost_at = std::chrono::steady_clock::now();
  ::close(hub_side);
  ASSERT_FALSE(daemon.WaitForLine("lost", kHubWaitMs).empty()) << daemon.output();
  auto second = std::async(std::launch::async, [&hub] { return hub.Accept(); });
  const int hub_side2 = second.get();
  ASSERT_GE(hub_side2, 0) << daemon.output();
  EXPECT_EQ(TcpqTestHub::ReadSubscribe(hub_side2), "CANALID_ASCE2_COMMAND") << daemon.output();
  ASSERT_FALSE(daemon.WaitForLine("reconnected", kHubWaitMs).empty()) << daemon.output();
  const double back_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - lost_at).count();
  std::printf("tcpq hub lost and reconnected in %.3f s\n", back_s);

  // Lost for good: nothing listens any more. The daemon retries with a doubling backoff and
  // stays up; SIGTERM still stops it cleanly.
  hub.StopListening();
  ::close(hub_side2);
  const std::string retry = daemon.WaitForLine("reconnecting in 0.2", kHubWaitMs);
  EXPECT_FALSE(retry.empty()) << daemon.output();
  EXPECT_EQ(daemon.output().find("fatal"), std::string::npos) << daemon.output();
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.output();
}

}  // namespace
}  // namespace canalid::testing
