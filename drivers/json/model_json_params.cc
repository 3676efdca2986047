#include "drivers/json/model_json_params.h"

#include <algorithm>
#include <array>
#include <limits>

namespace canalid::drivers {
namespace {

bool AllNumbers(const nlohmann::json& v) {
  return v.is_array() &&
         std::all_of(v.begin(), v.end(), [](const nlohmann::json& x) { return x.is_number(); });
}

}  // namespace

std::vector<ModelJsonParam> ModelJsonParams(const nlohmann::json& model) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  // Each scalar with the key of its standard deviation where the fit gives one (idz).
  static constexpr std::array<std::array<const char*, 2>, 9> kKeys{
      {{"delay_s", nullptr},
       {"area_m2", "area_std_m2"},
       {"b", nullptr},
       {"p21_s_per_m2", "p21_std_s_per_m2"},
       {"p22_s_per_m2", "p22_std_s_per_m2"},
       {"offset_m", nullptr},
       {"gain", nullptr},
       {"time_constant_s", nullptr},
       {"alpha", nullptr}}};
  auto number = [&](const char* key) {
    return key != nullptr && model.contains(key) && model[key].is_number();
  };
  std::vector<ModelJsonParam> params;
  for (const auto& [key, std_key] : kKeys) {
    if (number(key)) {
      params.push_back(
          {key, model[key].get<double>(), number(std_key) ? model[std_key].get<double>() : kNan});
    }
  }
  // arx's coefficients (arrays in its JSON), named as the online arx kind names them.
  if (model.contains("a") && AllNumbers(model["a"]) && model.contains("b_coeffs") &&
      model["b_coeffs"].is_array() && model["b_coeffs"].size() == 1 &&
      AllNumbers(model["b_coeffs"][0])) {
    const nlohmann::json& a = model["a"];
    const nlohmann::json& b = model["b_coeffs"][0];
    for (std::size_t k = 0; k < a.size(); ++k)
      params.push_back({"a" + std::to_string(k + 1), a[k].get<double>(), kNan});
    for (std::size_t k = 0; k < b.size(); ++k)
      params.push_back({"b" + std::to_string(k + 1), b[k].get<double>(), kNan});
  }
  // soptd's two time constants (an array in its JSON), T1 >= T2.
  if (model.contains("time_constants_s") && AllNumbers(model["time_constants_s"]) &&
      model["time_constants_s"].size() == 2) {
    params.push_back({"time_constant_1_s", model["time_constants_s"][0].get<double>(), kNan});
    params.push_back({"time_constant_2_s", model["time_constants_s"][1].get<double>(), kNan});
  }
  // frac-ss's coefficients from its companion form (A's last row is -[a_n, ..., a_1], C is
  // [1, c_1, ..., c_{n-1}]), named as the online frac-ss kind names them.
  if (model.value("model", "") == "frac-ss" && model.contains("A") && model["A"].is_array() &&
      !model["A"].empty() && AllNumbers(model["A"].back()) && model.contains("C") &&
      AllNumbers(model["C"]) && model["C"].size() == model["A"].back().size() &&
      !model["C"].empty()) {
    const nlohmann::json& last_row = model["A"].back();
    const std::size_t n = last_row.size();
    for (std::size_t i = 1; i <= n; ++i)
      params.push_back({"a" + std::to_string(i), -last_row[n - i].get<double>(), kNan});
    for (std::size_t i = 1; i < n; ++i)
      params.push_back({"c" + std::to_string(i), model["C"][i].get<double>(), kNan});
  }
  // The process models' rest point (their deviations are taken from it), named as the online
  // process kinds name their operating point; no standard deviation (foptd, soptd and
  // frac-foptd fit the output's).
  if (number("input_offset") && number("output_offset")) {
    params.push_back({"input_operating_point", model["input_offset"].get<double>(), kNan});
    params.push_back({"level_operating_point_m", model["output_offset"].get<double>(), kNan});
  }
  return params;
}

}  // namespace canalid::drivers
