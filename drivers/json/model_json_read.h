#pragma once
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/arx.h"
#include "core/commensurate_state_space.h"
#include "core/fractional_foptd.h"
#include "core/fractional_simulator.h"
#include "core/id_model.h"
#include "core/lpv_model.h"
#include "core/process_models.h"

namespace canalid::drivers {

/// A model JSON that cannot be read back: the message names the source (file) and the key,
/// e.g. "m.json: key 'gain': missing".
class ModelJsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The inverse of the ToJson writers of model_json.h, for every kind `canalid identify` writes.
/// `source` names the file in error messages.  Each reader checks presence, type and range of the
/// keys it needs and ignores the rest (metrics, cross-checks, ...).
/// @throws ModelJsonError on a missing, mistyped or out-of-range key.

/// "id": the open-loop level equation y(k) = b Q(k) + p21 q_in(k - nk) + c + d (k - k0).
struct IdModelRecord {
  core::IdModel model;
  double p21_s_per_m2 = 0.0;
  double offset_m = 0.0;
  double drift_m_per_s = 0.0;
  int fit_from_sample = 0;  ///< k0
  bool closed_loop = false;
};
IdModelRecord IdModelFromJson(const nlohmann::json& json, const std::string& source);

/// "arx": orders, a and b_coeffs (parameters and statistics are not restored).
core::ArxModel ArxModelFromJson(const nlohmann::json& json, const std::string& source);

/// A continuous model in deviations: y = output_offset + G(s) (u - input_offset).
template <class Model>
struct OffsetModelRecord {
  Model model;
  double input_offset = 0.0;
  double output_offset = 0.0;
};
OffsetModelRecord<core::FoptdModel> FoptdFromJson(const nlohmann::json& json,
                                                  const std::string& source);
OffsetModelRecord<core::SoptdModel> SoptdFromJson(const nlohmann::json& json,
                                                  const std::string& source);

/// "frac-foptd" with the Oustaloup band it was simulated with.
struct FractionalFoptdRecord {
  OffsetModelRecord<core::FractionalFoptdParams> params;
  core::OustaloupOptions band;
};
FractionalFoptdRecord FractionalFoptdFromJson(const nlohmann::json& json,
                                              const std::string& source);

/// "frac-ss": the companion matrices A, B, C are checked to have seed 1's form for q.
struct CommensurateRecord {
  OffsetModelRecord<core::CommensurateModel> model;
  double sample_time_s = 0.0;
  int memory_length = 0;
};
CommensurateRecord CommensurateFromJson(const nlohmann::json& json, const std::string& source);

/// "lpv": the polynomial coefficients per parameter, in the order of "parameters".
struct LpvRecord {
  core::LpvModel model;
  std::string local_model;  ///< the CLI name of the local kind (arx, frac-foptd, ...)
  std::string schedule;     ///< scheduling column
  double input_offset = 0.0;
  double output_offset = 0.0;
};
LpvRecord LpvFromJson(const nlohmann::json& json, const std::string& source);

/// The "model" key.  @throws ModelJsonError when it is missing or not a string.
std::string ModelKind(const nlohmann::json& json, const std::string& source);

/// The "inputs" list (column names) or an empty list when absent.
std::vector<std::string> ModelInputs(const nlohmann::json& json, const std::string& source);

}  // namespace canalid::drivers
