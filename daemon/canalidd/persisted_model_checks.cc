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
  // Both pool models carry b, nk and the sample time; idz adds direct gains the checks need not.
  double b = 0.0, model_ts = 0.0;
  int nk = 0;
  try {
    if (persisted.model_kind == "id") {
      const drivers::IntegratorDelayModelRecord record =
          drivers::IntegratorDelayModelFromJson(j, "model");
      b = record.model.b;
      nk = record.model.nk;
      model_ts = record.model.sample_time_s;
    } else if (persisted.model_kind == "idz") {
      const drivers::IdzModelRecord record = drivers::IdzModelFromJson(j, "model");
      b = record.model.b;
      nk = record.model.nk;
      model_ts = record.sample_time_s;
    } else {
      return "model kind '" + persisted.model_kind + "' is not an integrator-delay model (id, idz)";
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  const double ts = bank.sample_time_s;
  std::ostringstream why;
  if (!std::isfinite(b)) {
    why << "b " << b << " is not finite";
  } else if (!j.contains("sample_time_s") || Differs(model_ts, ts)) {
    why << "sample_time_s " << (j.contains("sample_time_s") ? j.at("sample_time_s").dump() : "none")
        << " is not the reach's " << ts << " s";
  } else if (j.contains("delay_s") &&
             (!j.at("delay_s").is_number() || Differs(j.at("delay_s").get<double>(), nk * ts))) {
    why << "delay_s " << j.at("delay_s").dump() << " is not nk x sample_time_s = " << nk * ts;
  } else if (std::string bounds = core::IntegratorDelayBoundsProblem(ts / b, nk, bank);
             !bounds.empty()) {
    return bounds;
  } else if (j.contains("area_m2") &&
             (!j.at("area_m2").is_number() || Differs(j.at("area_m2").get<double>(), ts / b))) {
    why << "area_m2 " << j.at("area_m2").dump() << " is not sample_time_s / b = " << ts / b;
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
    } else if (persisted.model_kind == "arx") {
      const core::ArxModel model = drivers::ArxModelFromJson(j, "model");
      if (model.orders.nk.size() != 1) return "arx: one input expected";
      if (!model.a.allFinite() || !model.b.front().allFinite())
        return "arx: coefficients not finite";
      if (!j.contains("delay_s") || !j.at("delay_s").is_number()) return "arx: no delay_s";
      delay_s = j.at("delay_s").get<double>();
      if (Differs(delay_s, model.orders.nk.front() * sample_time_s)) {
        return "arx: delay_s " + j.at("delay_s").dump() + " is not nk x the reach's sample time";
      }
    } else if (persisted.model_kind == "soptd") {
      const auto record = drivers::SoptdFromJson(j, "model");
      gain = record.model.gain;
      delay_s = record.model.delay_s;
    } else if (persisted.model_kind == "frac-foptd") {
      const auto record = drivers::FractionalFoptdFromJson(j, "model");
      gain = record.params.model.gain;
      delay_s = record.params.model.delay_s;
    } else if (persisted.model_kind == "frac-ss") {
      const auto record = drivers::CommensurateFromJson(j, "model");
      const core::CommensurateModel& m = record.model.model;
      if (m.a(m.order() - 1) == 0.0) return "frac-ss: a_n is 0";
      delay_s = m.delay_samples * sample_time_s;
      if (!j.contains("delay_s") || !j.at("delay_s").is_number() ||
          Differs(j.at("delay_s").get<double>(), delay_s)) {
        return "frac-ss: delay_s is not delay_samples x the reach's sample time";
      }
    } else {
      return "model kind '" + persisted.model_kind +
             "' is not a process model (foptd, soptd, frac-foptd, arx, frac-ss)";
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
  if (model.model_kind == "id" || model.model_kind == "idz") {
    return PersistedIntegratorDelayProblem(model, bank);
  }
  return PersistedProcessModelProblem(model, bank.sample_time_s,
                                      bank.max_delay_samples * bank.sample_time_s);
}

}  // namespace canalid::daemon
