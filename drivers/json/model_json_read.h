#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd.h"
#include "core/fractional/fractional_simulator.h"
#include "core/fractional/lpv_model.h"
#include "core/integrator_delay/idz_fit.h"
#include "core/integrator_delay/integrator_delay_model.h"
#include "core/linear/arx.h"
#include "core/linear/process_models.h"

namespace canalid::drivers {

/// Largest "lpv" model read: polynomial degree and number of scheduled parameters (the CLI fits
/// degree 0..6; a first-order ARX local has 3 parameters, the largest local kind 2 q + 2).
inline constexpr int kMaxLpvDegree = 20;
inline constexpr std::size_t kMaxLpvParameters = 64;

/// A model JSON that cannot be read back: the message names the source (file) and the key,
/// e.g. "m.json: key 'gain': missing".
class ModelJsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The inverse of the ToJson writers of model_json.h, for every kind `canalid identify` writes.
/// `source` names the file in error messages.  Each reader checks presence, type and range of the
/// keys it needs and ignores the rest (metrics, cross-checks, ...).  The keys that define a model
/// are required; the others are optional with the defaults of docs/model-json.md (offsets 0, a
/// discrete model's sample time 0 = "the caller's record's", ...), so a model written by hand
/// from a paper needs only its parameters.
/// @throws ModelJsonError on a missing required key, or a mistyped or out-of-range key.

/// "id": the open-loop level equation y(k) = b Q(k) + p21 q_in(k - nk) + c + d (k - k0).
/// Required b, nk; model.sample_time_s is 0 when "sample_time_s" is absent (use the record's),
/// p21, offset and drift default to 0, fit_from_sample to nk + 1, closed_loop to false.
struct IntegratorDelayModelRecord {
  core::IntegratorDelayModel model;
  double p21_s_per_m2 = 0.0;
  double offset_m = 0.0;
  double drift_m_per_s = 0.0;
  int fit_from_sample = 0;  ///< k0
  bool closed_loop = false;
};
IntegratorDelayModelRecord IntegratorDelayModelFromJson(const nlohmann::json& json,
                                                        const std::string& source);

/// "idz": the level equation of core::IdzLevel.  Required b, nk; sample_time_s 0 when absent (use
/// the record's); p21, p22, offset and drift default to 0, fit_from_sample to nk + 1.
struct IdzModelRecord {
  core::IdzLevelModel model;
  double sample_time_s = 0.0;
  double drift_m_per_s = 0.0;
  int fit_from_sample = 0;  ///< k0
};
IdzModelRecord IdzModelFromJson(const nlohmann::json& json, const std::string& source);

/// "arx": orders, a and b_coeffs (parameters and statistics are not restored); first_sample from
/// "fit_from_sample", by default orders.min_first_sample() (the fit's own default).
core::ArxModel ArxModelFromJson(const nlohmann::json& json, const std::string& source);

/// A continuous model in deviations: y = output_offset + G(s) (u - input_offset); both offsets
/// default to 0.
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

/// "frac-foptd" with the Oustaloup band it was simulated with, when recorded ("oustaloup": any
/// of its three keys may be left out, or the whole object).
struct FractionalFoptdRecord {
  OffsetModelRecord<core::FractionalFoptdParams> params;
  std::optional<double> low_frequency_rad_s;
  std::optional<double> high_frequency_rad_s;
  std::optional<double> sections_per_decade;
  /// The band to simulate with: the recorded keys, the others as the fit chooses them for a
  /// record of `samples` at `sample_time_s` (core::FitOustaloupBand; 0 samples: its 1000 Ts
  /// floor), so a model the fit wrote and one written without the band simulate alike.
  /// @throws std::invalid_argument on sample_time_s <= 0.
  core::OustaloupOptions Band(double sample_time_s, Eigen::Index samples) const;
};
FractionalFoptdRecord FractionalFoptdFromJson(const nlohmann::json& json,
                                              const std::string& source);

/// "frac-ss": the companion matrices A, B, C are checked to have the LPV paper's form for q.
/// Required q, A, B, C, delay_samples; sample_time_s is 0 when absent (use the record's),
/// memory_length defaults to 0 (the whole record).
struct CommensurateRecord {
  OffsetModelRecord<core::CommensurateModel> model;
  double sample_time_s = 0.0;
  int memory_length = 0;
};
CommensurateRecord CommensurateFromJson(const nlohmann::json& json, const std::string& source);

/// "lpv": the polynomial coefficients per parameter, in the order of "parameters"; offsets
/// default to 0.
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
