// The model JSON readers invert the writers (drivers/json/model_json.h) and name the key of any
// problem.
#include "drivers/json/model_json_read.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/fractional/fractional_foptd_fit.h"
#include "drivers/json/model_json.h"
#include "tests/support/minimal_lpv_json.h"

namespace canalid::drivers {
namespace {

// Expects `call` to throw ModelJsonError whose message contains `text`.
template <class Call>
void ExpectError(Call call, const std::string& text) {
  try {
    call();
    ADD_FAILURE() << "no error, expected: " << text;
  } catch (const ModelJsonError& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

// The start of the reader's message about `key` of m.json.
std::string KeyError(const std::string& key) { return "m.json: key '" + key + "'"; }

TEST(ModelJsonReadTest, FractionalFoptdRoundTrip) {
  core::FractionalFoptdFitResult fit;
  fit.params = {0.372, 10.975, 0.83, 4.05};
  fit.input_offset = 20.0;
  fit.output_offset = 60.5;
  const core::OustaloupOptions band{1e-5, 333.0, 2.0};
  const nlohmann::json json = nlohmann::json::parse(ToJson(fit, band).dump());
  const FractionalFoptdRecord r = FractionalFoptdFromJson(json, "m.json");
  EXPECT_EQ(r.params.model.gain, 0.372);
  EXPECT_EQ(r.params.model.time_constant_s, 10.975);
  EXPECT_EQ(r.params.model.alpha, 0.83);
  EXPECT_EQ(r.params.model.delay_s, 4.05);
  EXPECT_EQ(r.params.input_offset, 20.0);
  EXPECT_EQ(r.params.output_offset, 60.5);
  // The recorded band wins over the fit's choice for any record.
  const core::OustaloupOptions read = r.Band(0.15, 2400);
  EXPECT_EQ(read.low_frequency_rad_s, 1e-5);
  EXPECT_EQ(read.high_frequency_rad_s, 333.0);
  EXPECT_EQ(read.sections_per_decade, 2.0);

  nlohmann::json bad = json;
  bad.erase("gain");
  ExpectError([&] { FractionalFoptdFromJson(bad, "m.json"); }, "m.json: key 'gain': missing");
  bad = json;
  bad["alpha"] = 2.0;
  ExpectError([&] { FractionalFoptdFromJson(bad, "m.json"); }, "key 'alpha': 2.0");
  bad = json;
  bad["time_constant_s"] = -1.0;
  ExpectError([&] { FractionalFoptdFromJson(bad, "m.json"); }, "key 'time_constant_s'");
  bad = json;
  bad["delay_s"] = "4";
  ExpectError([&] { FractionalFoptdFromJson(bad, "m.json"); }, "key 'delay_s': not a number");
  ExpectError([&] { FoptdFromJson(json, "m.json"); },
              "key 'model': 'frac-foptd', expected 'foptd'");
}

TEST(ModelJsonReadTest, CommensurateRoundTripAndCompanionForm) {
  core::CommensurateFitResult fit;
  fit.model.q = 2;
  fit.model.a = Eigen::Vector4d(2.1, 1.4, 0.7, 0.015);
  fit.model.c = Eigen::Vector3d(1.3, 0.7, 0.18);
  fit.model.delay_samples = 27;
  fit.input_offset = 20.0;
  fit.output_offset = 60.0;
  const nlohmann::json json = nlohmann::json::parse(ToJson(fit, 0.15, 0).dump());
  // The writer's A, B, C follow the header's companion form.
  EXPECT_EQ(json["A"][3][0].get<double>(), -0.015);  // -a_n first
  EXPECT_EQ(json["A"][3][3].get<double>(), -2.1);
  EXPECT_EQ(json["A"][0][1].get<double>(), 1.0);
  EXPECT_EQ(json["B"][3].get<double>(), 0.015);
  EXPECT_EQ(json["C"][0].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(json["delay_s"].get<double>(), 27 * 0.15);
  const CommensurateRecord r = CommensurateFromJson(json, "ss.json");
  EXPECT_EQ(r.model.model.q, 2);
  EXPECT_EQ(r.model.model.a, fit.model.a);
  EXPECT_EQ(r.model.model.c, fit.model.c);
  EXPECT_EQ(r.model.model.delay_samples, 27);
  EXPECT_EQ(r.sample_time_s, 0.15);

  nlohmann::json bad = json;
  bad["A"][0][0] = 0.5;
  ExpectError([&] { CommensurateFromJson(bad, "ss.json"); }, "ss.json: key 'A': not in companion");
  bad = json;
  bad["B"][3] = 1.0;
  ExpectError([&] { CommensurateFromJson(bad, "ss.json"); }, "key 'B'");
  bad = json;
  bad["q"] = 4;
  ExpectError([&] { CommensurateFromJson(bad, "ss.json"); }, "key 'A': needs 8 rows");
}

TEST(ModelJsonReadTest, LpvArxIdAndProcessModelsRoundTrip) {
  core::LpvIdentification lpv;
  lpv.model.kind = "first_order_arx";
  lpv.model.parameter_names = {"a1", "b1", "nk"};
  lpv.model.degree = 2;
  lpv.model.coefficients.resize(3, 3);
  lpv.model.coefficients << 0.05, -0.2, -0.7, -0.02, 0.1, 0.05, 0.0, 0.0, 3.0;
  nlohmann::json json = ToJson(lpv, 10.0);
  json["local_model"] = "arx";
  json["schedule"] = "upstream";
  json["input_offset"] = 0.0;
  json["output_offset"] = 1.5;
  const LpvRecord r = LpvFromJson(nlohmann::json::parse(json.dump()), "lpv.json");
  EXPECT_EQ(r.model.coefficients, lpv.model.coefficients);
  EXPECT_EQ(r.model.parameter_names, lpv.model.parameter_names);
  EXPECT_EQ(r.schedule, "upstream");
  json["coefficients"].erase("b1");
  ExpectError([&] { LpvFromJson(json, "lpv.json"); }, "key 'coefficients.b1': missing");

  core::ArxModel arx;
  arx.orders = {2, {2, 1}, {1, 2}};
  arx.a = Eigen::Vector2d(-1.5, 0.7);
  arx.b = {Eigen::Vector2d(1.0, 0.5), Eigen::VectorXd::Constant(1, 0.3)};
  arx.first_sample = 2;
  const core::ArxModel a = ArxModelFromJson(ToJson(arx), "arx.json");
  EXPECT_EQ(a.a, arx.a);
  EXPECT_EQ(a.b[0], arx.b[0]);
  EXPECT_EQ(a.b[1], arx.b[1]);
  EXPECT_EQ(a.orders.nk, arx.orders.nk);
  EXPECT_EQ(a.first_sample, 2);
  nlohmann::json bad_arx = ToJson(arx);
  bad_arx["b_coeffs"][1] = {0.3, 0.1};
  ExpectError([&] { ArxModelFromJson(bad_arx, "arx.json"); }, "key 'b_coeffs': list 1 has 2");

  core::IntegratorDelayFit id;
  id.model = {60.0 / 34113.0, 11, 60.0};
  id.wave_front_gain_s_per_m2 = 1e-5;
  id.offset_m = 2.1;
  id.drift_m_per_sample = 6e-6;
  id.first_sample = 40;
  const IntegratorDelayModelRecord i = IntegratorDelayModelFromJson(ToJson(id), "id.json");
  EXPECT_EQ(i.model.b, id.model.b);
  EXPECT_EQ(i.model.nk, 11);
  EXPECT_DOUBLE_EQ(i.drift_m_per_s * 60.0, 6e-6);
  EXPECT_EQ(i.fit_from_sample, 40);

  core::SoptdFit soptd;
  soptd.model = {0.4, {12.0, 3.0}, 2.5};
  soptd.output_offset = 7.0;
  const auto s = SoptdFromJson(ToJson(soptd), "s.json");
  EXPECT_EQ(s.model.time_constants_s[1], 3.0);
  EXPECT_EQ(s.output_offset, 7.0);
  ExpectError([&] { SoptdFromJson(nlohmann::json::array(), "s.json"); },
              "s.json: key 'model': the model is not a JSON object");
}

// The minimal forms of docs/model-json.md: the keys that define each model, nothing else.
nlohmann::json Minimal(const std::string& kind) {
  using nlohmann::json;
  if (kind == "id") return json{{"model", "id"}, {"b", 0.00176}, {"nk", 11}};
  if (kind == "arx") {
    return json{{"model", "arx"}, {"na", 2},          {"nb", {2, 1}},
                {"nk", {1, 2}},   {"a", {-1.5, 0.7}}, {"b_coeffs", {{1.0, 0.5}, {0.3}}}};
  }
  if (kind == "foptd") {
    return json{{"model", "foptd"}, {"gain", 0.4}, {"time_constant_s", 12.0}, {"delay_s", 2.5}};
  }
  if (kind == "soptd") {
    return json{
        {"model", "soptd"}, {"gain", 0.4}, {"time_constants_s", {12.0, 3.0}}, {"delay_s", 2.5}};
  }
  if (kind == "frac-foptd") {
    return json{{"model", "frac-foptd"},
                {"gain", 0.372},
                {"time_constant_s", 10.975},
                {"alpha", 0.8},
                {"delay_s", 0.0}};
  }
  if (kind == "frac-ss") {
    return json{{"model", "frac-ss"}, {"q", 1},          {"A", {{0.0, 1.0}, {-0.5, -1.5}}},
                {"B", {0.0, 0.5}},    {"C", {1.0, 0.2}}, {"delay_samples", 3}};
  }
  return canalid::testing::MinimalLpvJson();
}

// Reads `json` with the reader of its kind (the result is dropped: only errors matter here).
void Read(const nlohmann::json& json, const std::string& kind) {
  if (kind == "id") IntegratorDelayModelFromJson(json, "m.json");
  if (kind == "arx") ArxModelFromJson(json, "m.json");
  if (kind == "foptd") FoptdFromJson(json, "m.json");
  if (kind == "soptd") SoptdFromJson(json, "m.json");
  if (kind == "frac-foptd") FractionalFoptdFromJson(json, "m.json");
  if (kind == "frac-ss") CommensurateFromJson(json, "m.json");
  if (kind == "lpv") LpvFromJson(json, "m.json");
}

TEST(ModelJsonReadTest, MinimalFormsTakeTheDocumentedDefaults) {
  const IntegratorDelayModelRecord id = IntegratorDelayModelFromJson(Minimal("id"), "m.json");
  EXPECT_EQ(id.model.sample_time_s, 0.0);  // the caller's record's
  EXPECT_EQ(id.p21_s_per_m2, 0.0);
  EXPECT_EQ(id.offset_m, 0.0);
  EXPECT_EQ(id.drift_m_per_s, 0.0);
  EXPECT_EQ(id.fit_from_sample, 12);  // nk + 1
  EXPECT_FALSE(id.closed_loop);
  EXPECT_EQ(ArxModelFromJson(Minimal("arx"), "m.json").first_sample, 2);  // max(na, nb + nk - 1)
  const auto foptd = FoptdFromJson(Minimal("foptd"), "m.json");
  EXPECT_EQ(foptd.input_offset, 0.0);
  EXPECT_EQ(foptd.output_offset, 0.0);
  EXPECT_EQ(SoptdFromJson(Minimal("soptd"), "m.json").output_offset, 0.0);
  const CommensurateRecord ss = CommensurateFromJson(Minimal("frac-ss"), "m.json");
  EXPECT_EQ(ss.sample_time_s, 0.0);
  EXPECT_EQ(ss.memory_length, 0);
  EXPECT_EQ(ss.model.input_offset, 0.0);
  EXPECT_EQ(LpvFromJson(Minimal("lpv"), "m.json").output_offset, 0.0);

  // frac-foptd: the band is the fit's for the record, key by key when only some are given.
  const FractionalFoptdRecord frac = FractionalFoptdFromJson(Minimal("frac-foptd"), "m.json");
  EXPECT_EQ(frac.params.input_offset, 0.0);
  const core::OustaloupOptions fit =
      core::FitOustaloupBand(frac.params.model, 0.15, 2400, core::FractionalFoptdFitOptions{});
  const core::OustaloupOptions band = frac.Band(0.15, 2400);
  EXPECT_EQ(band.low_frequency_rad_s, fit.low_frequency_rad_s);
  EXPECT_EQ(band.high_frequency_rad_s, fit.high_frequency_rad_s);
  EXPECT_EQ(band.sections_per_decade, 2.0);  // the fit's density, not the simulator's default 3
  nlohmann::json partial = Minimal("frac-foptd");
  partial["oustaloup"] = {{"sections_per_decade", 4.0}};
  const core::OustaloupOptions dense = FractionalFoptdFromJson(partial, "m.json").Band(0.15, 2400);
  EXPECT_EQ(dense.sections_per_decade, 4.0);
  EXPECT_EQ(dense.low_frequency_rad_s, fit.low_frequency_rad_s);
}

TEST(ModelJsonReadTest, MinimalFormsNameEveryMissingOrMistypedKey) {
  const std::map<std::string, std::vector<std::string>> required = {
      {"id", {"b", "nk"}},
      {"arx", {"na", "nb", "nk", "a", "b_coeffs"}},
      {"foptd", {"gain", "time_constant_s", "delay_s"}},
      {"soptd", {"gain", "time_constants_s", "delay_s"}},
      {"frac-foptd", {"gain", "time_constant_s", "alpha", "delay_s"}},
      {"frac-ss", {"q", "A", "B", "C", "delay_samples"}},
      {"lpv", {"kind", "local_model", "schedule", "degree", "parameters", "coefficients"}}};
  for (const auto& [required_kind, keys] : required) {
    const std::string& kind = required_kind;  // a lambda cannot capture a structured binding in
                                              // clang 14 (C++20 allows it; GCC does)
    SCOPED_TRACE(kind);
    EXPECT_NO_THROW(Read(Minimal(kind), kind));
    for (const std::string& key : keys) {
      nlohmann::json json = Minimal(kind);
      json.erase(key);
      ExpectError([&] { Read(json, kind); }, KeyError(key) + ": missing");
      json[key] = nullptr;  // present but of no type a reader takes
      ExpectError([&] { Read(json, kind); }, KeyError(key));
    }
  }
  // Optional keys are checked when present.
  const std::vector<std::pair<std::string, std::string>> optional = {
      {"id", "sample_time_s"},        {"id", "p21_s_per_m2"},      {"id", "offset_m"},
      {"id", "drift_m_per_s"},        {"id", "fit_from_sample"},   {"id", "closed_loop"},
      {"arx", "fit_from_sample"},     {"foptd", "input_offset"},   {"soptd", "output_offset"},
      {"frac-foptd", "input_offset"}, {"frac-foptd", "oustaloup"}, {"frac-ss", "sample_time_s"},
      {"frac-ss", "memory_length"},   {"lpv", "output_offset"}};
  for (const auto& entry : optional) {
    const std::string& kind = entry.first;
    const std::string& key = entry.second;
    SCOPED_TRACE(::testing::Message() << kind << " " << key);
    nlohmann::json json = Minimal(kind);
    json[key] = "x";
    ExpectError([&] { Read(json, kind); }, KeyError(key));
  }
  nlohmann::json band = Minimal("frac-foptd");
  band["oustaloup"] = {{"low_frequency_rad_s", -1.0}};
  ExpectError([&] { Read(band, "frac-foptd"); }, "m.json: oustaloup: key 'low_frequency_rad_s'");
  band["oustaloup"] = {{"low_frequency_rad_s", 10.0}, {"high_frequency_rad_s", 1.0}};
  ExpectError([&] { Read(band, "frac-foptd"); }, "key 'oustaloup': high_frequency_rad_s must");
  nlohmann::json id = Minimal("id");
  id["fit_from_sample"] = 5;  // nk = 11
  ExpectError([&] { Read(id, "id"); }, "key 'fit_from_sample': 5 must be > nk = 11");
}

// Regression: the readers sized arrays from integers in the file before checking them (an "lpv"
// "degree": 100000000 with 8 parameter names reserved 6.4 GB before the coefficient lists were
// looked at), and "arx" orders or an Oustaloup density far beyond what can run went through.
TEST(ModelJsonReadTest, OrdersAndSizesAreCheckedAgainstStatedBoundsBeforeUse) {
  nlohmann::json lpv = Minimal("lpv");
  lpv["degree"] = 100000000;
  ExpectError([&] { Read(lpv, "lpv"); },
              "m.json: key 'degree': 100000000 is out of range (allowed: 0..20)");
  lpv = Minimal("lpv");
  lpv["parameters"] = std::vector<std::string>(65, "a1");
  ExpectError([&] { Read(lpv, "lpv"); }, "key 'parameters': needs a list of 1..64 names");
  nlohmann::json arx = Minimal("arx");
  arx["nk"] = {2147483647, 2};
  ExpectError([&] { Read(arx, "arx"); }, "key 'nk'");
  arx["nk"] = {100000000, 2};  // within the reader's integer range, beyond the ARX bound
  ExpectError([&] { Read(arx, "arx"); },
              "key 'na/nb/nk': ArxOrders.nk[0] = 100000000 is out of range (allowed: 0..10000000)");
  nlohmann::json band = Minimal("frac-foptd");
  band["oustaloup"] = {{"sections_per_decade", 1000.0}};
  ExpectError([&] { Read(band, "frac-foptd"); },
              "m.json: oustaloup: key 'sections_per_decade': 1000.000000 is out of range");
}

}  // namespace
}  // namespace canalid::drivers
