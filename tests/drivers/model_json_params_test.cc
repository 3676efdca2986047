// drivers/json/model_json_params.h: the parameters of a model JSON as a snapshot publishes them,
// against hand-written JSON.
#include "drivers/json/model_json_params.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace canalid::drivers {
namespace {

std::vector<std::string> Names(const std::vector<ModelJsonParam>& params) {
  std::vector<std::string> names;
  names.reserve(params.size());
  for (const ModelJsonParam& p : params) names.push_back(p.name);
  return names;
}

TEST(ModelJsonParams, ScalarsWithTheirStandardDeviationsInTheSnapshotsOrder) {
  const nlohmann::json idz = {
      {"model", "idz"},      {"area_m2", 100.0},           {"area_std_m2", 5.0}, {"delay_s", 60.0},
      {"p21_s_per_m2", 0.1}, {"metrics", {{"rmse", 1.0}}}, {"reach", "pool2"}};
  const std::vector<ModelJsonParam> p = ModelJsonParams(idz);
  EXPECT_EQ(Names(p), (std::vector<std::string>{"delay_s", "area_m2", "p21_s_per_m2"}));
  EXPECT_EQ(p[1].value, 100.0);
  EXPECT_EQ(p[1].std_dev, 5.0);
  EXPECT_TRUE(std::isnan(p[0].std_dev));
  EXPECT_TRUE(std::isnan(p[2].std_dev));  // no p21_std_s_per_m2 given
}

TEST(ModelJsonParams, ArxAndSoptdArraysAreFlattenedByName) {
  const nlohmann::json arx = {
      {"model", "arx"}, {"delay_s", 0.3}, {"a", {-0.9, 0.1}}, {"b_coeffs", {{0.2, 0.3, 0.4}}}};
  const std::vector<ModelJsonParam> p = ModelJsonParams(arx);
  EXPECT_EQ(Names(p), (std::vector<std::string>{"delay_s", "a1", "a2", "b1", "b2", "b3"}));
  EXPECT_EQ(p[2].value, 0.1);
  EXPECT_EQ(p[5].value, 0.4);
  const nlohmann::json soptd = {
      {"model", "soptd"}, {"gain", 0.5}, {"time_constants_s", {8.0, 2.0}}, {"delay_s", 3.0}};
  EXPECT_EQ(
      Names(ModelJsonParams(soptd)),
      (std::vector<std::string>{"delay_s", "gain", "time_constant_1_s", "time_constant_2_s"}));
  EXPECT_EQ(ModelJsonParams(soptd)[3].value, 2.0);
}

// The rest point a process model's deviations are taken from, published as the online process
// kinds publish their operating point (no standard deviation: some kinds fit it).
TEST(ModelJsonParams, ProcessOffsetsAreTheOperatingPoint) {
  const nlohmann::json arx = {{"model", "arx"},      {"delay_s", 0.3},
                              {"a", {-0.9}},         {"b_coeffs", {{0.2}}},
                              {"input_offset", 1.5}, {"output_offset", 2.25}};
  const std::vector<ModelJsonParam> p = ModelJsonParams(arx);
  EXPECT_EQ(Names(p), (std::vector<std::string>{"delay_s", "a1", "b1", "input_operating_point",
                                                "level_operating_point_m"}));
  EXPECT_EQ(p[3].value, 1.5);
  EXPECT_EQ(p[4].value, 2.25);
  EXPECT_TRUE(std::isnan(p[4].std_dev));
  const nlohmann::json one_offset = {{"model", "foptd"}, {"gain", 0.5}, {"input_offset", 1.0}};
  EXPECT_EQ(Names(ModelJsonParams(one_offset)), (std::vector<std::string>{"gain"}));
}

// frac-ss's coefficients from its companion form: A's last row is -[a2, a1], C is [1, c1].
TEST(ModelJsonParams, FracSsCoefficientsComeFromItsCompanionForm) {
  const nlohmann::json frac_ss = {
      {"model", "frac-ss"}, {"q", 1},           {"alpha", 1.0},  {"A", {{0.0, 1.0}, {-0.1, -0.5}}},
      {"B", {0.0, 0.1}},    {"C", {1.0, 0.25}}, {"delay_s", 6.0}};
  const std::vector<ModelJsonParam> p = ModelJsonParams(frac_ss);
  EXPECT_EQ(Names(p), (std::vector<std::string>{"delay_s", "alpha", "a1", "a2", "c1"}));
  EXPECT_EQ(p[2].value, 0.5);
  EXPECT_EQ(p[3].value, 0.1);
  EXPECT_EQ(p[4].value, 0.25);
  nlohmann::json ragged = frac_ss;
  ragged["C"] = {1.0};  // not one per state: left out
  EXPECT_EQ(Names(ModelJsonParams(ragged)), (std::vector<std::string>{"delay_s", "alpha"}));
}

TEST(ModelJsonParams, MalformedOrMultiInputArraysAreLeftOut) {
  const nlohmann::json two_inputs = {{"a", {-0.9}}, {"b_coeffs", {{0.1}, {0.2}}}};
  EXPECT_TRUE(ModelJsonParams(two_inputs).empty());
  const nlohmann::json text = {
      {"a", {"x"}}, {"b_coeffs", {{0.1}}}, {"time_constants_s", {1.0}}, {"gain", "high"}};
  EXPECT_TRUE(ModelJsonParams(text).empty());
}

}  // namespace
}  // namespace canalid::drivers
