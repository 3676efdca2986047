#include "daemon/canalidd/persisted_model_checks.h"

#include <cmath>
#include <sstream>

#include "drivers/json/model_json_read.h"

namespace canalid::daemon {
namespace {

bool Differs(double a, double b) { return !(std::abs(a - b) <= 1e-6 * std::abs(b)); }

}  // namespace

std::string PersistedIntegratorDelayProblem(const PersistedModel& persisted,
                                            const core::OnlineIntegratorDelayOptions& bank) {
  const nlohmann::json& j = persisted.model;
  if (persisted.model_kind != "id") {
    return "model kind '" + persisted.model_kind + "' is not an integrator-delay model (id)";
  }
  drivers::IntegratorDelayModelRecord record;
  try {
    record = drivers::IntegratorDelayModelFromJson(j, "model");
  } catch (const std::exception& e) {
    return e.what();
  }
  const core::IntegratorDelayModel& m = record.model;
  const double ts = bank.sample_time_s;
  std::ostringstream why;
  if (!std::isfinite(m.b)) {
    why << "b " << m.b << " is not finite";
  } else if (!j.contains("sample_time_s") || Differs(m.sample_time_s, ts)) {
    why << "sample_time_s " << (j.contains("sample_time_s") ? j.at("sample_time_s").dump() : "none")
        << " is not the reach's " << ts << " s";
  } else if (j.contains("delay_s") &&
             (!j.at("delay_s").is_number() || Differs(j.at("delay_s").get<double>(), m.nk * ts))) {
    why << "delay_s " << j.at("delay_s").dump() << " is not nk x sample_time_s = " << m.nk * ts;
  } else if (std::string bounds = core::IntegratorDelayBoundsProblem(ts / m.b, m.nk, bank);
             !bounds.empty()) {
    return bounds;
  } else if (j.contains("area_m2") &&
             (!j.at("area_m2").is_number() || Differs(j.at("area_m2").get<double>(), ts / m.b))) {
    why << "area_m2 " << j.at("area_m2").dump() << " is not sample_time_s / b = " << ts / m.b;
  }
  return why.str();
}

std::string PersistedProcessModelProblem(const PersistedModel& persisted, double sample_time_s,
                                         double max_delay_s) {
  const nlohmann::json& j = persisted.model;
  double gain = 0.0, delay_s = 0.0;
  try {
    if (persisted.model_kind == "foptd") {
      const auto record = drivers::FoptdFromJson(j, "model");
      gain = record.model.gain;
      delay_s = record.model.delay_s;
    } else if (persisted.model_kind == "frac-foptd") {
      const auto record = drivers::FractionalFoptdFromJson(j, "model");
      gain = record.params.model.gain;
      delay_s = record.params.model.delay_s;
    } else {
      return "model kind '" + persisted.model_kind + "' is not a process model (foptd, frac-foptd)";
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  std::ostringstream why;
  if (!j.contains("sample_time_s") || !j.at("sample_time_s").is_number() ||
      Differs(j.at("sample_time_s").get<double>(), sample_time_s)) {
    why << "sample_time_s " << (j.contains("sample_time_s") ? j.at("sample_time_s").dump() : "none")
        << " is not the reach's " << sample_time_s << " s";
  } else if (!std::isfinite(gain)) {
    why << "gain " << gain << " is not finite";
  } else if (!(delay_s >= 0.0 && delay_s <= max_delay_s)) {
    why << "delay_s " << delay_s << " is outside [0, " << max_delay_s << "] s";
  }
  return why.str();
}

std::string PersistedModelProblem(const PersistedModel& model,
                                  const core::OnlineIntegratorDelayOptions& bank) {
  if (model.model_kind == "id") return PersistedIntegratorDelayProblem(model, bank);
  return PersistedProcessModelProblem(model, bank.sample_time_s,
                                      bank.max_delay_samples * bank.sample_time_s);
}

}  // namespace canalid::daemon
