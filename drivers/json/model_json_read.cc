#include "drivers/json/model_json_read.h"

#include <cmath>
#include <optional>

#include "core/fractional/fractional_foptd_fit.h"
#include "core/fractional/oustaloup.h"

namespace canalid::drivers {
namespace {

using nlohmann::json;

[[noreturn]] void Fail(const std::string& source, const std::string& key,
                       const std::string& problem) {
  throw ModelJsonError(source + ": key '" + key + "': " + problem);
}

const json& Get(const json& j, const std::string& key, const std::string& source) {
  if (!j.is_object()) Fail(source, key, "the model is not a JSON object");
  const auto it = j.find(key);
  if (it == j.end()) Fail(source, key, "missing");
  return *it;
}

double Number(const json& j, const std::string& key, const std::string& source) {
  const json& v = Get(j, key, source);
  if (!v.is_number()) Fail(source, key, "not a number: " + v.dump());
  const double x = v.get<double>();
  if (!std::isfinite(x)) Fail(source, key, "not finite");
  return x;
}

// An optional number: `fallback` when the key is absent, else checked as Number.
double NumberOr(const json& j, const std::string& key, const std::string& source, double fallback) {
  if (!j.is_object() || !j.contains(key)) return fallback;
  return Number(j, key, source);
}

double Positive(const json& j, const std::string& key, const std::string& source) {
  const double x = Number(j, key, source);
  if (!(x > 0.0)) Fail(source, key, std::to_string(x) + " must be > 0");
  return x;
}

double NonNegative(const json& j, const std::string& key, const std::string& source) {
  const double x = Number(j, key, source);
  if (!(x >= 0.0)) Fail(source, key, std::to_string(x) + " must be >= 0");
  return x;
}

int Integer(const json& j, const std::string& key, const std::string& source, int min) {
  const json& v = Get(j, key, source);
  if (!v.is_number_integer()) Fail(source, key, "not a whole number: " + v.dump());
  const long long x = v.get<long long>();
  if (x < min || x > 100000000) {
    Fail(source, key, std::to_string(x) + " must be in [" + std::to_string(min) + ", 1e8]");
  }
  return static_cast<int>(x);
}

std::vector<double> NumberList(const json& v, const std::string& key, const std::string& source) {
  if (!v.is_array()) Fail(source, key, "not a list of numbers: " + v.dump());
  std::vector<double> out;
  for (const json& x : v) {
    if (!x.is_number() || !std::isfinite(x.get<double>())) {
      Fail(source, key, "not a list of finite numbers: " + v.dump());
    }
    out.push_back(x.get<double>());
  }
  return out;
}

Eigen::VectorXd Vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::vector<int> IntList(const json& j, const std::string& key, const std::string& source) {
  const json& v = Get(j, key, source);
  if (!v.is_array()) Fail(source, key, "not a list of whole numbers: " + v.dump());
  std::vector<int> out;
  for (const json& x : v) {
    if (!x.is_number_integer() || x.get<long long>() < 0 || x.get<long long>() > 100000000) {
      Fail(source, key, "not a list of whole numbers >= 0: " + v.dump());
    }
    out.push_back(static_cast<int>(x.get<long long>()));
  }
  return out;
}

void ExpectKind(const json& j, const std::string& kind, const std::string& source) {
  const std::string found = ModelKind(j, source);
  if (found != kind) Fail(source, "model", "'" + found + "', expected '" + kind + "'");
}

// Optional: the model in deviations from 0 when the offsets are left out.
template <class Model>
void ReadOffsets(const json& j, const std::string& source, OffsetModelRecord<Model>& record) {
  record.input_offset = NumberOr(j, "input_offset", source, 0.0);
  record.output_offset = NumberOr(j, "output_offset", source, 0.0);
}

// An optional sample time: 0 when absent (the caller takes its record's), else > 0.
double SampleTimeOrZero(const json& j, const std::string& source) {
  if (!j.is_object() || !j.contains("sample_time_s")) return 0.0;
  return Positive(j, "sample_time_s", source);
}

std::optional<double> OptionalPositive(const json& j, const std::string& key,
                                       const std::string& source) {
  if (!j.contains(key)) return std::nullopt;
  return Positive(j, key, source);
}

// k0 of a pool model ("fit_from_sample", default nk + 1), which must come after the delay.
int FitFromSample(const json& j, const std::string& source, int nk) {
  const int k0 = j.contains("fit_from_sample") ? Integer(j, "fit_from_sample", source, 0) : nk + 1;
  if (k0 < nk + 1) {
    Fail(source, "fit_from_sample", std::to_string(k0) + " must be > nk = " + std::to_string(nk));
  }
  return k0;
}

}  // namespace

std::string ModelKind(const json& j, const std::string& source) {
  const json& v = Get(j, "model", source);
  if (!v.is_string()) Fail(source, "model", "not a string: " + v.dump());
  return v.get<std::string>();
}

std::vector<std::string> ModelInputs(const json& j, const std::string& source) {
  std::vector<std::string> names;
  if (!j.is_object() || !j.contains("inputs")) return names;
  const json& v = j.at("inputs");
  if (!v.is_array()) Fail(source, "inputs", "not a list of column names: " + v.dump());
  for (const json& x : v) {
    if (!x.is_string()) Fail(source, "inputs", "not a list of column names: " + v.dump());
    names.push_back(x.get<std::string>());
  }
  return names;
}

IntegratorDelayModelRecord IntegratorDelayModelFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "id", source);
  IntegratorDelayModelRecord r;
  r.model.b = Number(j, "b", source);
  r.model.nk = Integer(j, "nk", source, 0);
  r.model.sample_time_s = SampleTimeOrZero(j, source);
  r.p21_s_per_m2 = NumberOr(j, "p21_s_per_m2", source, 0.0);
  r.offset_m = NumberOr(j, "offset_m", source, 0.0);
  r.drift_m_per_s = NumberOr(j, "drift_m_per_s", source, 0.0);
  r.fit_from_sample = FitFromSample(j, source, r.model.nk);
  if (j.contains("closed_loop")) {
    const json& closed = j.at("closed_loop");
    if (!closed.is_boolean()) Fail(source, "closed_loop", "not true or false: " + closed.dump());
    r.closed_loop = closed.get<bool>();
  }
  return r;
}

IdzModelRecord IdzModelFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "idz", source);
  IdzModelRecord r;
  r.model.b = Number(j, "b", source);
  r.model.nk = Integer(j, "nk", source, 0);
  r.sample_time_s = SampleTimeOrZero(j, source);
  r.model.p21_s_per_m2 = NumberOr(j, "p21_s_per_m2", source, 0.0);
  r.model.p22_s_per_m2 = NumberOr(j, "p22_s_per_m2", source, 0.0);
  r.model.offset_m = NumberOr(j, "offset_m", source, 0.0);
  r.drift_m_per_s = NumberOr(j, "drift_m_per_s", source, 0.0);
  r.fit_from_sample = FitFromSample(j, source, r.model.nk);
  return r;
}

core::ArxModel ArxModelFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "arx", source);
  core::ArxModel m;
  m.orders.na = Integer(j, "na", source, 0);
  m.orders.nb = IntList(j, "nb", source);
  m.orders.nk = IntList(j, "nk", source);
  const std::size_t inputs = m.orders.nb.size();
  if (m.orders.nk.size() != inputs) Fail(source, "nk", "needs one value per input (as nb)");
  try {
    m.orders.Validate(static_cast<Eigen::Index>(inputs));
  } catch (const std::invalid_argument& e) {
    Fail(source, "na/nb/nk", e.what());
  }
  const std::vector<double> a = NumberList(Get(j, "a", source), "a", source);
  if (a.size() != static_cast<std::size_t>(m.orders.na)) {
    Fail(source, "a", std::to_string(a.size()) + " values but na = " + std::to_string(m.orders.na));
  }
  m.a = Vector(a);
  const json& b = Get(j, "b_coeffs", source);
  if (!b.is_array() || b.size() != inputs) {
    Fail(source, "b_coeffs", "needs one list per input (" + std::to_string(inputs) + ")");
  }
  for (std::size_t i = 0; i < inputs; ++i) {
    const std::vector<double> bi = NumberList(b[i], "b_coeffs", source);
    if (bi.size() != static_cast<std::size_t>(m.orders.nb[i])) {
      Fail(source, "b_coeffs",
           "list " + std::to_string(i) + " has " + std::to_string(bi.size()) +
               " values but nb = " + std::to_string(m.orders.nb[i]));
    }
    m.b.push_back(Vector(bi));
  }
  m.first_sample = j.contains("fit_from_sample") ? Integer(j, "fit_from_sample", source, 0)
                                                 : m.orders.min_first_sample();
  return m;
}

OffsetModelRecord<core::FoptdModel> FoptdFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "foptd", source);
  OffsetModelRecord<core::FoptdModel> r;
  r.model.gain = Number(j, "gain", source);
  r.model.time_constant_s = Positive(j, "time_constant_s", source);
  r.model.delay_s = NonNegative(j, "delay_s", source);
  ReadOffsets(j, source, r);
  return r;
}

OffsetModelRecord<core::SoptdModel> SoptdFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "soptd", source);
  OffsetModelRecord<core::SoptdModel> r;
  r.model.gain = Number(j, "gain", source);
  const std::vector<double> t =
      NumberList(Get(j, "time_constants_s", source), "time_constants_s", source);
  if (t.size() != 2 || !(t[0] > 0.0) || !(t[1] > 0.0)) {
    Fail(source, "time_constants_s", "needs two values > 0");
  }
  r.model.time_constants_s = {t[0], t[1]};
  r.model.delay_s = NonNegative(j, "delay_s", source);
  ReadOffsets(j, source, r);
  return r;
}

FractionalFoptdRecord FractionalFoptdFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "frac-foptd", source);
  FractionalFoptdRecord r;
  core::FractionalFoptdParams& p = r.params.model;
  p.gain = Number(j, "gain", source);
  p.time_constant_s = Positive(j, "time_constant_s", source);
  p.alpha = Positive(j, "alpha", source);
  if (!(p.alpha < 2.0)) Fail(source, "alpha", std::to_string(p.alpha) + " must be < 2");
  p.delay_s = NonNegative(j, "delay_s", source);
  ReadOffsets(j, source, r.params);
  if (!j.contains("oustaloup")) return r;
  const json& band = j.at("oustaloup");
  if (!band.is_object()) Fail(source, "oustaloup", "not an object: " + band.dump());
  const std::string where = source + ": oustaloup";
  r.low_frequency_rad_s = OptionalPositive(band, "low_frequency_rad_s", where);
  r.high_frequency_rad_s = OptionalPositive(band, "high_frequency_rad_s", where);
  r.sections_per_decade = OptionalPositive(band, "sections_per_decade", where);
  if (r.sections_per_decade && !(*r.sections_per_decade <= core::kMaxOustaloupSectionsPerDecade)) {
    Fail(where, "sections_per_decade",
         std::to_string(*r.sections_per_decade) + " is out of range (allowed: > 0 and <= 20)");
  }
  if (r.low_frequency_rad_s && r.high_frequency_rad_s &&
      !(*r.high_frequency_rad_s > *r.low_frequency_rad_s)) {
    Fail(source, "oustaloup", "high_frequency_rad_s must exceed low_frequency_rad_s");
  }
  return r;
}

CommensurateRecord CommensurateFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "frac-ss", source);
  CommensurateRecord r;
  core::CommensurateModel& m = r.model.model;
  m.q = Integer(j, "q", source, 1);
  if (m.q > 64) Fail(source, "q", std::to_string(m.q) + " must be <= 64");
  const int n = m.order();
  const json& a = Get(j, "A", source);
  if (!a.is_array() || a.size() != static_cast<std::size_t>(n)) {
    Fail(source, "A", "needs " + std::to_string(n) + " rows (n = 2 q)");
  }
  m.a.resize(n);
  for (int i = 0; i < n; ++i) {
    const std::vector<double> row = NumberList(a[static_cast<std::size_t>(i)], "A", source);
    if (row.size() != static_cast<std::size_t>(n)) {
      Fail(source, "A", "row " + std::to_string(i) + " needs " + std::to_string(n) + " values");
    }
    for (int k = 0; k < n; ++k) {
      const double value = row[static_cast<std::size_t>(k)];
      if (i + 1 == n) {
        m.a(n - 1 - k) = -value;
      } else if (value != (k == i + 1 ? 1.0 : 0.0)) {
        Fail(source, "A",
             "not in companion form (ones on the superdiagonal) at row " + std::to_string(i));
      }
    }
  }
  const std::vector<double> b = NumberList(Get(j, "B", source), "B", source);
  if (b.size() != static_cast<std::size_t>(n)) Fail(source, "B", "needs n = 2 q values");
  for (int k = 0; k + 1 < n; ++k) {
    if (b[static_cast<std::size_t>(k)] != 0.0) Fail(source, "B", "must be a_n e_n");
  }
  if (b.back() != m.a(n - 1)) Fail(source, "B", "last value must equal a_n = -A[n-1][0]");
  const std::vector<double> c = NumberList(Get(j, "C", source), "C", source);
  if (c.size() != static_cast<std::size_t>(n) || c.front() != 1.0) {
    Fail(source, "C", "needs n = 2 q values starting with 1");
  }
  m.c = Vector(c).tail(n - 1);
  m.delay_samples = Integer(j, "delay_samples", source, 0);
  r.sample_time_s = SampleTimeOrZero(j, source);
  r.memory_length = j.contains("memory_length") ? Integer(j, "memory_length", source, 0) : 0;
  ReadOffsets(j, source, r.model);
  return r;
}

LpvRecord LpvFromJson(const json& j, const std::string& source) {
  ExpectKind(j, "lpv", source);
  LpvRecord r;
  const json& kind = Get(j, "kind", source);
  const json& local = Get(j, "local_model", source);
  const json& schedule = Get(j, "schedule", source);
  if (!kind.is_string()) Fail(source, "kind", "not a string");
  if (!local.is_string()) Fail(source, "local_model", "not a string");
  if (!schedule.is_string()) Fail(source, "schedule", "not a string");
  r.model.kind = kind.get<std::string>();
  r.local_model = local.get<std::string>();
  r.schedule = schedule.get<std::string>();
  r.model.degree = Integer(j, "degree", source, 0);
  if (r.model.degree > kMaxLpvDegree) {
    Fail(source, "degree",
         std::to_string(r.model.degree) + " is out of range (allowed: 0.." +
             std::to_string(kMaxLpvDegree) + ")");
  }
  const json& names = Get(j, "parameters", source);
  if (!names.is_array() || names.empty() || names.size() > kMaxLpvParameters) {
    Fail(source, "parameters",
         "needs a list of 1.." + std::to_string(kMaxLpvParameters) + " names");
  }
  const json& coefficients = Get(j, "coefficients", source);
  if (!coefficients.is_object()) {
    Fail(source, "coefficients", "not an object (parameter name -> list): " + coefficients.dump());
  }
  // Every list is read and checked before the matrix is sized from them.
  std::vector<std::vector<double>> rows;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!names[i].is_string()) Fail(source, "parameters", "not a list of names");
    const std::string name = names[i].get<std::string>();
    r.model.parameter_names.push_back(name);
    const std::string key = "coefficients." + name;
    if (!coefficients.contains(name)) Fail(source, key, "missing");
    rows.push_back(NumberList(coefficients.at(name), key, source));
    if (rows.back().size() != static_cast<std::size_t>(r.model.degree) + 1) {
      Fail(source, key, "needs degree + 1 = " + std::to_string(r.model.degree + 1) + " values");
    }
  }
  r.model.coefficients.resize(static_cast<Eigen::Index>(rows.size()), r.model.degree + 1);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    r.model.coefficients.row(static_cast<Eigen::Index>(i)) = Vector(rows[i]).transpose();
  }
  r.input_offset = NumberOr(j, "input_offset", source, 0.0);
  r.output_offset = NumberOr(j, "output_offset", source, 0.0);
  return r;
}

core::OustaloupOptions FractionalFoptdRecord::Band(double sample_time_s,
                                                   Eigen::Index samples) const {
  core::OustaloupOptions band = core::FitOustaloupBand(params.model, sample_time_s, samples);
  if (low_frequency_rad_s) band.low_frequency_rad_s = *low_frequency_rad_s;
  if (high_frequency_rad_s) band.high_frequency_rad_s = *high_frequency_rad_s;
  if (sections_per_decade) band.sections_per_decade = *sections_per_decade;
  return band;
}

}  // namespace canalid::drivers
