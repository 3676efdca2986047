#pragma once
#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "sim/sampled_plant.h"

namespace canalid::sim {

/// The kinds PlantFromModelJson builds, for messages and --help.
inline constexpr const char* kModelPlantKinds =
    "id, idz, arx, foptd, soptd, frac-foptd, frac-ss, lpv";

/// The plant of a `canalid identify` model JSON (read with drivers/json/model_json_read.h), with
/// the conventions of `canalid simulate`, so the two give the same output on the same input:
/// - "id": IntegratorDelayLevelPlant, inputs (q_in, q_out), the model's own sample time (the
/// plant's when the
///   model has none); `initial_inputs(0)`
///   is the inflow before sample 0.
/// - "foptd": FractionalFoptdPlant with alpha = 1 (exact ZOH first order); "frac-foptd": with
///   the model's alpha and recorded Oustaloup band (without one: the fit's band for 1000
///   samples, as the run's length is not known; `canalid simulate` uses its record's length,
///   so the two agree only when the band is recorded); "soptd": SoptdPlant (exact ZOH second order,
///   sub-sample delay).  One input; `initial_inputs(0)` = u[0], the input the plant rests at
///   when it starts (y = output_offset + K (u[0] - input_offset) + G(s) (u - u[0])).
/// - "frac-ss": CommensuratePlant with the record's memory_length (0 = full memory, whose cost
///   grows with the run) and offsets, at rest at `initial_inputs(0)` like the continuous kinds;
///   only at the model's sample time.
/// - "lpv" (arx locals only): LpvArxPlant, inputs (u, theta) = the input and the scheduling
///   variable; at rest at input_offset (not at `initial_inputs`), as `canalid simulate --model
///   lpv`; the delay ring covers nk(theta) over the bands widened by their span on each side.
/// - "arx": ArxPlant, as many inputs as the model, the model's sample time when recorded; its
///   first outputs are `initial_outputs` (`canalid simulate` uses the first max(first_sample, 1)
///   measured outputs).
/// Part of the canalsim program (library canalsim_lib), not of canalid_sim: it reads the JSON
/// with drivers/, and the simulator library depends on core only.
/// @throws drivers::ModelJsonError on a bad record, std::invalid_argument on another kind
///         (or lpv with a local model other than arx, or without bands), a sample time that does
///         not match a discrete model (id, arx, frac-ss, lpv), or empty initial inputs.
std::unique_ptr<SampledPlant> PlantFromModelJson(
    const nlohmann::json& json, const std::string& source, double sample_time_s,
    const Eigen::Ref<const Eigen::VectorXd>& initial_inputs,
    const Eigen::VectorXd& initial_outputs = Eigen::VectorXd());

}  // namespace canalid::sim
