#include "sim/canalsim/model_plant_json.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "drivers/json/model_json_read.h"
#include "sim/commensurate_plant.h"
#include "sim/lpv_arx_plant.h"
#include "sim/soptd_plant.h"

namespace canalid::sim {
namespace {

void RequireInitialInputs(const Eigen::Ref<const Eigen::VectorXd>& initial_inputs,
                          const std::string& source) {
  if (initial_inputs.size() < 1) {
    throw std::invalid_argument(source + ": initial_inputs is empty, needs the first input");
  }
}

// Discrete models (nk, ARX coefficients) mean nothing at another sampling.
void RequireSampleTime(double model_s, double sample_time_s, const std::string& source) {
  if (std::abs(sample_time_s - model_s) > 1e-9 * model_s) {
    throw std::invalid_argument(source + ": sample_time_s = " + std::to_string(sample_time_s) +
                                " but the model is discrete at " + std::to_string(model_s) + " s");
  }
}

// The longest delay of an LPV ARX model over its bands widened by their span on each side (the
// schedule may leave the identified range a little; further out the polynomials mean little).
int LpvDelayBound(const nlohmann::json& json, const std::string& source, const LpvArxPlant& plant) {
  const auto bands = json.find("bands");
  if (bands == json.end() || !bands->is_array() || bands->size() < 2) {
    throw std::invalid_argument(source + ": key 'bands': needs the band edges (at least 2)");
  }
  std::vector<double> edges;
  for (const auto& edge : *bands) {
    if (!edge.is_number()) throw std::invalid_argument(source + ": key 'bands': not a number list");
    edges.push_back(edge.get<double>());
  }
  const auto [low, high] = std::minmax_element(edges.begin(), edges.end());
  const double span = *high - *low;
  constexpr int kPoints = 4001;
  long longest = 1;
  for (int i = 0; i < kPoints; ++i) {
    const double theta = *low - span + 3.0 * span * i / (kPoints - 1);
    longest = std::max(longest, plant.DelaySamples(theta));
  }
  // A delay law this long is a broken record, not a canal (and the ring would not fit).
  constexpr long kMaxDelaySamples = 1000000;
  if (longest > kMaxDelaySamples) {
    throw std::invalid_argument(source + ": key 'coefficients.nk': delays up to " +
                                std::to_string(longest) + " samples over the bands, at most " +
                                std::to_string(kMaxDelaySamples));
  }
  return static_cast<int>(longest);
}

std::unique_ptr<SampledPlant> LpvPlant(const nlohmann::json& json, const std::string& source,
                                       double sample_time_s) {
  const drivers::LpvRecord r = drivers::LpvFromJson(json, source);
  if (r.model.kind != "first_order_arx") {
    throw std::invalid_argument(source + ": key 'local_model': '" + r.local_model +
                                "': an lpv plant exists for arx locals only");
  }
  if (json.contains("sample_time_s") && json.at("sample_time_s").is_number()) {
    RequireSampleTime(json.at("sample_time_s").get<double>(), sample_time_s, source);
  }
  const LpvArxPlant probe(r.model, sample_time_s, r.input_offset, r.output_offset, 1);
  return std::make_unique<LpvArxPlant>(r.model, sample_time_s, r.input_offset, r.output_offset,
                                       LpvDelayBound(json, source, probe));
}

}  // namespace

std::unique_ptr<SampledPlant> PlantFromModelJson(
    const nlohmann::json& json, const std::string& source, double sample_time_s,
    const Eigen::Ref<const Eigen::VectorXd>& initial_inputs,
    const Eigen::VectorXd& initial_outputs) {
  RequireInitialInputs(initial_inputs, source);
  const std::string kind = drivers::ModelKind(json, source);
  if (kind == "id") {
    drivers::IntegratorDelayModelRecord r = drivers::IntegratorDelayModelFromJson(json, source);
    // A model written without its sample time runs at the plant's.
    if (r.model.sample_time_s > 0.0) {
      RequireSampleTime(r.model.sample_time_s, sample_time_s, source);
    } else {
      r.model.sample_time_s = sample_time_s;
    }
    return std::make_unique<IntegratorDelayLevelPlant>(r.model, r.p21_s_per_m2, r.offset_m,
                                                       r.drift_m_per_s * r.model.sample_time_s,
                                                       r.fit_from_sample, initial_inputs(0));
  }
  if (kind == "idz") {
    const drivers::IdzModelRecord r = drivers::IdzModelFromJson(json, source);
    if (r.sample_time_s > 0.0) RequireSampleTime(r.sample_time_s, sample_time_s, source);
    const core::IntegratorDelayModel model{r.model.b, r.model.nk, sample_time_s};
    // The IDZ level equation's q_in(k - nk) term is (p21 - b) (core::IdzLevel).
    return std::make_unique<IntegratorDelayLevelPlant>(
        model, r.model.p21_s_per_m2 - r.model.b, r.model.offset_m, r.drift_m_per_s * sample_time_s,
        r.fit_from_sample, initial_inputs(0), r.model.p22_s_per_m2);
  }
  if (kind == "arx") {
    const core::ArxModel arx = drivers::ArxModelFromJson(json, source);
    if (json.value("input_offset", 0.0) != 0.0 || json.value("output_offset", 0.0) != 0.0) {
      throw std::invalid_argument(source +
                                  ": input_offset/output_offset: an arx model of deviations from "
                                  "a rest point (the daemon's batch arx) is not a plant here; "
                                  "fit the raw columns with canalid identify --model arx");
    }
    if (json.contains("sample_time_s") && json.at("sample_time_s").is_number()) {
      RequireSampleTime(json.at("sample_time_s").get<double>(), sample_time_s, source);
    }
    return std::make_unique<ArxPlant>(arx, sample_time_s, initial_outputs);
  }
  if (kind == "foptd") {
    const auto r = drivers::FoptdFromJson(json, source);
    const core::FractionalFoptdParams params{r.model.gain, r.model.time_constant_s, 1.0,
                                             r.model.delay_s};
    // alpha = 1 takes the exact first-order branch; the band is only validated.
    return std::make_unique<FractionalFoptdPlant>(
        params, core::DefaultOustaloupOptions(params, sample_time_s, 1000.0 * sample_time_s),
        sample_time_s, r.input_offset, r.output_offset, initial_inputs(0));
  }
  if (kind == "frac-foptd") {
    const drivers::FractionalFoptdRecord r = drivers::FractionalFoptdFromJson(json, source);
    // A run has no length known in advance: without a recorded band, the fit's band for a
    // record of 1000 samples (FractionalFoptdRecord::Band's floor).
    return std::make_unique<FractionalFoptdPlant>(r.params.model, r.Band(sample_time_s, 0),
                                                  sample_time_s, r.params.input_offset,
                                                  r.params.output_offset, initial_inputs(0));
  }
  if (kind == "soptd") {
    const auto r = drivers::SoptdFromJson(json, source);
    return std::make_unique<SoptdPlant>(r.model, sample_time_s, r.input_offset, r.output_offset,
                                        initial_inputs(0));
  }
  if (kind == "frac-ss") {
    const drivers::CommensurateRecord r = drivers::CommensurateFromJson(json, source);
    if (r.sample_time_s > 0.0) RequireSampleTime(r.sample_time_s, sample_time_s, source);
    return std::make_unique<CommensuratePlant>(r.model.model, r.memory_length, sample_time_s,
                                               r.model.input_offset, r.model.output_offset,
                                               initial_inputs(0));
  }
  if (kind == "lpv") return LpvPlant(json, source, sample_time_s);
  throw std::invalid_argument(source + ": key 'model': '" + kind + "' has no plant (" +
                              kModelPlantKinds + ")");
}

}  // namespace canalid::sim
