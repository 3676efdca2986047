#pragma once
#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "sim/sampled_plant.h"

namespace canalid::sim {

/// The plant of a `canalid identify` model JSON (read with drivers/json/model_json_read.h), with
/// the conventions of `canalid simulate`, so the two give the same output on the same input:
/// - "id": IdLevelPlant, inputs (q_in, q_out), the model's own sample time; `initial_inputs(0)`
///   is the inflow before sample 0.
/// - "foptd": FractionalFoptdPlant with alpha = 1 (exact ZOH first order); "frac-foptd": with
///   the model's alpha and recorded Oustaloup band.  One input; `initial_inputs(0)` = u[0], the
///   input the plant rests at when it starts.
/// - "arx": ArxPlant, as many inputs as the model, the model's sample time when recorded; its
///   first outputs are `initial_outputs` (`canalid simulate` uses the first max(first_sample, 1)
///   measured outputs).
/// Lives in its own library (canalid_sim_json) because sim/ does not depend on drivers/.
/// @throws drivers::ModelJsonError on a bad record, std::invalid_argument on another kind
///         (soptd, frac-ss, lpv have no plant yet), a sample time that does not match a
///         discrete model, or a wrong number of initial inputs.
std::unique_ptr<SampledPlant> PlantFromModelJson(
    const nlohmann::json& json, const std::string& source, double sample_time_s,
    const Eigen::Ref<const Eigen::VectorXd>& initial_inputs,
    const Eigen::VectorXd& initial_outputs = Eigen::VectorXd());

}  // namespace canalid::sim
