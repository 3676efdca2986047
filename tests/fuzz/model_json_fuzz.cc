// Model JSON (drivers/json/model_json_read.h): the bytes are parsed as JSON, as `canalid
// simulate` and `canalsim plant` read a model file, and handed to every reader, whatever the
// "model" key says (each reader checks the keys it needs).  Expected: a JSON parse error, and
// ModelJsonError from a reader (std::invalid_argument from a core model's own checks, and from
// FractionalFoptdRecord::Band).  Anything else escaping a reader breaks its contract.
#include <nlohmann/json.hpp>

#include <stdexcept>

#include "drivers/json/model_json_read.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

template <class F>
void Expect(F read) {
  try {
    read();
  } catch (const canalid::drivers::ModelJsonError&) {
  } catch (const std::invalid_argument&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace drivers = canalid::drivers;
  const nlohmann::json json = nlohmann::json::parse(data, data + size, nullptr, false);
  if (json.is_discarded()) return 0;  // not JSON: the programs report the parse error
  const std::string source = "fuzz.json";
  Expect([&] { drivers::ModelKind(json, source); });
  Expect([&] { drivers::ModelInputs(json, source); });
  Expect([&] { drivers::IntegratorDelayModelFromJson(json, source); });
  Expect([&] { drivers::ArxModelFromJson(json, source); });
  Expect([&] { drivers::FoptdFromJson(json, source); });
  Expect([&] { drivers::SoptdFromJson(json, source); });
  Expect([&] {
    const drivers::FractionalFoptdRecord record = drivers::FractionalFoptdFromJson(json, source);
    record.Band(1.0, 1000);
  });
  Expect([&] { drivers::CommensurateFromJson(json, source); });
  Expect([&] { drivers::LpvFromJson(json, source); });
  return 0;
}
