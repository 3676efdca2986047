#include "core/online/online_model.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/online/online_model_kinds.h"
#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

constexpr std::array<std::string_view, kOnlineModelKinds.size()> kKindNames{
    "id", "arx", "frac-foptd", "lpv", "idz", "frac-ss"};

// Largest delay or memory a setting may ask for, in samples (the banks allocate per sample).
constexpr double kMaxSettingSamples = 1e6;

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineModelSettings", name, value, range);
}

// round(seconds / Ts) samples, the one rounding of a duration the online estimators use.
int Samples(const char* name, double seconds, double sample_time_s) {
  if (!(std::isfinite(seconds) && seconds >= 0.0)) Fail(name, seconds, "finite, >= 0 s");
  const double samples = std::round(seconds / sample_time_s);
  if (!(samples <= kMaxSettingSamples)) Fail(name, seconds, "at most 1e6 samples");
  return static_cast<int>(samples);
}

}  // namespace

RlsOptions RlsOptionsFor(const OnlineModelSettings& s, int num_params) {
  RlsOptions rls;
  rls.method = s.rls_method;
  rls.forgetting = s.forgetting;
  rls.initial_covariance = s.initial_covariance.value_or(kDefaultInitialCovariance);
  // Constant trace holds a finite trace: the initial one.
  if (rls.method == RlsMethod::kConstantTrace) {
    rls.trace_max = num_params * rls.initial_covariance;
  }
  return rls;
}

std::string_view OnlineModelKindName(OnlineModelKind kind) {
  return kKindNames[static_cast<std::size_t>(kind)];
}

std::optional<OnlineModelKind> OnlineModelKindFromName(std::string_view name) {
  for (const OnlineModelKind kind : kOnlineModelKinds) {
    if (OnlineModelKindName(kind) == name) return kind;
  }
  return std::nullopt;
}

OnlineModelOptions OnlineModelOptionsFor(OnlineModelKind kind, const OnlineModelSettings& s) {
  if (!(s.sample_time_s > 0.0 && std::isfinite(s.sample_time_s))) {
    Fail("sample_time_s", s.sample_time_s, "finite, > 0");
  }
  if (s.initial_covariance && !(*s.initial_covariance > 0.0 && *s.initial_covariance <= 1e20)) {
    Fail("initial_covariance", *s.initial_covariance, "0 < p0 <= 1e20");
  }
  OnlineModelOptions o;
  o.kind = kind;
  o.sample_time_s = s.sample_time_s;
  switch (kind) {
    case OnlineModelKind::kIntegratorDelay:
      o.id.sample_time_s = s.sample_time_s;
      o.id.min_delay_samples = Samples("min_delay_s", s.min_delay_s, s.sample_time_s);
      o.id.max_delay_samples = Samples("max_delay_s", s.max_delay_s, s.sample_time_s);
      o.id.wave_front_term = s.wave_front_term;
      o.id.wave_front_non_negative = s.wave_front_term;
      o.id.rls = RlsOptionsFor(s, s.wave_front_term ? 4 : 3);
      o.id.closed_loop = s.closed_loop;
      o.id.outflow_direct_gain_s_per_m2 = s.p22_s_per_m2;
      break;
    case OnlineModelKind::kIdz:
      o.id.sample_time_s = s.sample_time_s;
      o.id.min_delay_samples = Samples("min_delay_s", s.min_delay_s, s.sample_time_s);
      o.id.max_delay_samples = Samples("max_delay_s", s.max_delay_s, s.sample_time_s);
      o.id.wave_front_term = true;
      o.id.wave_front_non_negative = true;
      o.id.idz_level_equation = true;
      o.id.rls = RlsOptionsFor(s, 4);
      o.id.closed_loop = s.closed_loop;
      o.id.outflow_direct_gain_s_per_m2 = s.idz_p22_s_per_m2;
      break;
    case OnlineModelKind::kArx:
      o.arx.na = s.arx_na;
      o.arx.nb = s.arx_nb;
      o.arx.min_delay_samples = Samples("min_delay_s", s.min_delay_s, s.sample_time_s);
      o.arx.max_delay_samples = Samples("max_delay_s", s.max_delay_s, s.sample_time_s);
      o.arx.rls = RlsOptionsFor(s, s.arx_na + s.arx_nb);
      break;
    case OnlineModelKind::kFractionalFoptd:
      o.fractional.sample_time_s = s.sample_time_s;
      o.fractional.alphas = s.fractional_alphas;
      o.fractional.delay_samples =
          Samples("fractional_delay_s", s.fractional_delay_s, s.sample_time_s);
      if (s.fractional_memory_s != 0.0) {
        o.fractional.memory_samples =
            Samples("fractional_memory_s", s.fractional_memory_s, s.sample_time_s);
      }
      o.fractional.rls = RlsOptionsFor(s, 2);
      break;
    case OnlineModelKind::kLpvArx:
      o.lpv.na = s.lpv_na;
      o.lpv.nb = s.lpv_nb;
      o.lpv.delay_samples = Samples("lpv_delay_s", s.lpv_delay_s, s.sample_time_s);
      o.lpv.rls = RlsOptionsFor(s, 3 * (s.lpv_na + s.lpv_nb));
      break;
    case OnlineModelKind::kFracSs:
      o.frac_ss.q = s.frac_ss_q;
      o.frac_ss.delay_samples = Samples("frac_ss_delay_s", s.frac_ss_delay_s, s.sample_time_s);
      if (s.fractional_memory_s != 0.0) {
        o.frac_ss.memory_samples =
            Samples("fractional_memory_s", s.fractional_memory_s, s.sample_time_s);
      }
      o.frac_ss.rls = RlsOptionsFor(s, o.frac_ss.num_params());
      break;
  }
  o.Validate();
  return o;
}

void OnlineModelOptions::Validate() const {
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    ThrowOptionOutOfRange("OnlineModelOptions", "sample_time_s", sample_time_s, "finite, > 0");
  }
  if (!(condition_max > 1.0)) {
    ThrowOptionOutOfRange("OnlineModelOptions", "condition_max", condition_max, "> 1");
  }
  switch (kind) {
    case OnlineModelKind::kIntegratorDelay:
    case OnlineModelKind::kIdz:
      id.Validate();
      break;
    case OnlineModelKind::kArx:
      arx.Validate();
      break;
    case OnlineModelKind::kFractionalFoptd:
      fractional.Validate();
      break;
    case OnlineModelKind::kLpvArx:
      lpv.Validate();
      break;
    case OnlineModelKind::kFracSs:
      frac_ss.Validate();
      break;
  }
}

double OnlineModelSnapshot::Value(std::string_view name) const {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return values[i];
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::unique_ptr<OnlineModel> MakeOnlineModel(const OnlineModelOptions& options) {
  options.Validate();
  switch (options.kind) {
    case OnlineModelKind::kIntegratorDelay:
    case OnlineModelKind::kIdz:
      return MakeOnlineIntegratorDelayModel(options);
    case OnlineModelKind::kArx:
      return MakeOnlineArxModel(options);
    case OnlineModelKind::kFractionalFoptd:
      return MakeOnlineFractionalModel(options);
    case OnlineModelKind::kLpvArx:
      return MakeOnlineLpvModel(options);
    case OnlineModelKind::kFracSs:
      return MakeOnlineFracSsModel(options);
  }
  throw std::invalid_argument("MakeOnlineModel: unknown kind");
}

int RlsHealthFlags(const RlsHealth& health, double condition, double condition_max,
                   bool values_finite) {
  int flags = 0;
  if (!values_finite || !std::isfinite(health.trace_p)) flags |= kFlagNan;
  if (health.wound_up) flags |= kFlagWindup;
  if (health.frozen) flags |= kFlagFrozen;
  if (!(condition <= condition_max)) flags |= kFlagIllConditioned;
  return flags;
}

SnapshotWriter::SnapshotWriter(OnlineModelSnapshot& out, OnlineModelKind kind,
                               std::string_view estimator, bool valid, std::int64_t samples_used,
                               std::span<const std::string> names)
    : out_(out) {
  out_.kind = kind;
  out_.estimator = estimator;
  out_.valid = valid;
  out_.samples_used = samples_used;
  out_.names = names;
  out_.num_params = static_cast<int>(names.size());
}

void SnapshotWriter::Put(double value, double std_dev) {
  finite_ = finite_ && std::isfinite(value);
  out_.values[next_] = value;
  out_.std_devs[next_++] = std_dev;
}

void SnapshotWriter::Finish(const RlsHealth& health, double condition, double excitation,
                            double error_rms, double condition_max, int extra_flags) {
  out_.trace_p = health.trace_p;
  out_.condition_number = condition;
  out_.excitation = excitation;
  out_.prediction_error_rms = error_rms;
  out_.flags =
      out_.valid ? RlsHealthFlags(health, condition, condition_max, finite_) | extra_flags : 0;
}

ProcessOnlineModel::ProcessOnlineModel(const OnlineModelOptions& options,
                                       std::vector<std::string> names)
    : names_(std::move(names)),
      sample_time_s_(options.sample_time_s),
      condition_max_(options.condition_max) {
  names_.emplace_back("input_operating_point");
  names_.emplace_back("level_operating_point_m");
}

ProcessOnlineModel::Deviations ProcessOnlineModel::Deviate(const OnlineSample& sample) {
  point_.Observe(sample.input, sample.level_m);
  return {point_.InputDeviation(sample.input), point_.OutputDeviation(sample.level_m)};
}

SnapshotWriter ProcessOnlineModel::Writer(OnlineModelSnapshot& out, std::string_view estimator,
                                          bool valid, std::int64_t samples_used) const {
  return SnapshotWriter(out, kind(), estimator, valid, samples_used, names_);
}

void ProcessOnlineModel::PutOperatingPoint(SnapshotWriter& writer, double level_offset,
                                           double level_offset_std) const {
  writer.Put(point_.input(), 0.0);
  writer.Put(point_.output() + level_offset, level_offset_std);
}

}  // namespace canalid::core
