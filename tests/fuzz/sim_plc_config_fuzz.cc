// canalsim's PLC emulation (sim/plc/plc_config.h): ParsePlcConfig, the reader behind
// LoadPlcConfig, for the ASCE test canal 2 of config/sim/asce-canal2.toml.  A rejected input must
// be a ConfigError; an accepted one must pass ValidatePlcConfig (what `canalsim serve` runs).
#include <stdexcept>
#include <string>

#include "sim/canal_config.h"
#include "sim/plc/plc_config.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const canalid::sim::Canal kCanal =
      canalid::sim::LoadCanal(std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal2.toml");
  canalid::sim::plc::PlcConfig config;
  try {
    config =
        canalid::sim::plc::ParsePlcConfig(canalid::fuzz::Text(data, size), "fuzz.toml", kCanal);
  } catch (const canalid::sim::ConfigError&) {
    return 0;
  }
  try {
    canalid::sim::plc::ValidatePlcConfig(config);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s\n", e.what());
    canalid::fuzz::Check(false, "an accepted PLC configuration is valid");
  }
  return 0;
}
