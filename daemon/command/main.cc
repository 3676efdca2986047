// canalid-command: signs one operator command with the shared key and publishes it on LCM.
//   canalid-command --key F --channel C --reach R start|stop|reset|publish-config [--counter N]
// The counter defaults to the current time in microseconds, which increases from one call to the
// next, so repeated calls are not taken for replays.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include "canalid/version.h"
#include "core/system/guarded_main.h"
#include "daemon/canalidd/key_file.h"
#include "drivers/auth/command_auth.h"
#include "drivers/lcm/bus.h"
#include "drivers/lcm/command_sender.h"
#include "drivers/lcm/lcm_bus.h"

namespace {

int64_t NowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string DefaultSender() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') return "operator";
  return std::string("operator@") + host;
}

int Main(int argc, char** argv) {
  using canalid::drivers::CommandKind;
  CLI::App app{"Sign a canalid operator command with the shared key and publish it on LCM."};
  std::string key_path, url, channel = "CANALID_COMMAND", reach, argument, action;
  std::string sender = DefaultSender();
  int64_t counter = 0;
  int64_t utime_us = 0;
  const std::map<std::string, CommandKind> kinds = {
      {"start", CommandKind::kStartExperiment},
      {"stop", CommandKind::kAbortExperiment},
      {"reset", CommandKind::kResetEstimator},
      {"publish-config", CommandKind::kPublishConfig}};
  app.add_option("--key", key_path,
                 "key file (mode 0600; 64 hex digits and an optional newline: openssl rand -hex "
                 "32)")
      ->required();
  app.add_option("--url", url, "LCM URL; empty = LCM's default ($LCM_DEFAULT_URL)");
  app.add_option("--channel", channel,
                 "command channel (the daemon's prefix + CANALID_COMMAND); signed, so it must be "
                 "the daemon's")
      ->capture_default_str();
  app.add_option("--reach", reach, "target reach")->required();
  app.add_option("--sender", sender, "sender id (its counter is tracked separately)")
      ->capture_default_str();
  app.add_option("--argument", argument, "kind-specific argument, e.g. the experiment name");
  app.add_option("--counter", counter,
                 "counter > 0, strictly increasing per sender; default: now in us");
  app.add_option("--utime-us", utime_us, "timestamp to sign (us since epoch); default: now");
  app.add_option("action", action, "start | stop | reset | publish-config")
      ->required()
      ->check(CLI::IsMember({"start", "stop", "reset", "publish-config"}));
  app.set_version_flag("--version", "canalid-command " + std::string(canalid::kVersion));
  CLI11_PARSE(app, argc, argv);

  try {
    canalid::drivers::SecretBytes key = canalid::daemon::ReadKeyFile(key_path);
    const int64_t now_us = NowUs();
    canalid::drivers::CommandFields fields;
    fields.channel = channel;
    fields.utime_us = utime_us != 0 ? utime_us : now_us;
    fields.counter = counter != 0 ? counter : now_us;
    fields.sender = sender;
    fields.kind = static_cast<int8_t>(kinds.at(action));
    fields.reach = reach;
    fields.argument = argument;
    const canalid::command_t message = canalid::drivers::BuildSignedCommand(key.span(), fields);
    key.Wipe();  // not needed for publishing
    canalid::drivers::LcmBus bus(url);
    std::vector<uint8_t> buffer;
    if (!canalid::drivers::PublishMessage(bus, channel, message, buffer)) {
      std::fprintf(stderr, "canalid-command: publishing on %s failed\n", channel.c_str());
      return 1;
    }
    std::printf("sent %s reach=%s sender=%s counter=%lld on %s\n", action.c_str(), reach.c_str(),
                sender.c_str(), static_cast<long long>(fields.counter), channel.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "canalid-command: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  return canalid::core::GuardedMain("canalid-command", Main, argc, argv);
}
