// canalsim's canal description (sim/canal_config.h): ParseCanal, the reader behind LoadCanal.  A
// rejected input must be a ConfigError (every problem, or the validation's message).
#include "sim/canal_config.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const canalid::sim::Canal canal =
        canalid::sim::ParseCanal(canalid::fuzz::Text(data, size), "fuzz.toml");
    canalid::fuzz::Check(!canal.pools.empty(), "an accepted canal has pools");
  } catch (const canalid::sim::ConfigError&) {
  }
  return 0;
}
