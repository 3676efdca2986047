// canalidd's TOML configuration (daemon/config/config_loader.h): ParseDaemonConfig, the parser
// behind LoadDaemonConfig and `canalid replay`'s reading of a logged configuration.  A rejected
// input must be a ConfigError; an accepted one must survive the round trip the header promises,
// ParseDaemonConfig(RenderDaemonConfig(c)) == c.
#include <string>

#include "daemon/config/config_loader.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using canalid::daemon::ConfigError;
  canalid::config::DaemonConfig config;
  try {
    config = canalid::daemon::ParseDaemonConfig(canalid::fuzz::Text(data, size), "fuzz.toml");
  } catch (const ConfigError&) {
    return 0;  // a rejected configuration, with every problem: expected
  }
  const std::string rendered = canalid::daemon::RenderDaemonConfig(config);
  try {
    canalid::fuzz::Check(canalid::daemon::ParseDaemonConfig(rendered, "rendered.toml") == config,
                         "ParseDaemonConfig(RenderDaemonConfig(c)) == c");
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "rendered configuration rejected:\n%s\n%s\n", rendered.c_str(), e.what());
    canalid::fuzz::Check(false, "RenderDaemonConfig(c) of an accepted c parses");
  }
  return 0;
}
