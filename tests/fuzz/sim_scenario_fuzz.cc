// canalsim's scenarios (sim/scenario.h): ParseScenario, the reader behind LoadScenario, for the
// ASCE test canal 2 of config/sim/asce-canal2.toml (whose scenarios seed the corpus).  A rejected
// input must be a ConfigError.
#include <string>

#include "sim/canal_config.h"
#include "sim/scenario.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const canalid::sim::Canal kCanal =
      canalid::sim::LoadCanal(std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal2.toml");
  try {
    const canalid::sim::Scenario scenario =
        canalid::sim::ParseScenario(canalid::fuzz::Text(data, size), "fuzz.toml", kCanal);
    canalid::fuzz::Check(
        scenario.duration_s > 0.0 && scenario.output_period_s > 0.0 && scenario.time_step_s > 0.0,
        "an accepted scenario has positive times");
    canalid::fuzz::Check(!scenario.canal.pools.empty(), "an accepted scenario simulates pools");
  } catch (const canalid::sim::ConfigError&) {
  }
  return 0;
}
