#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/online/online_arx.h"
#include "core/online/online_commensurate.h"
#include "core/online/online_fractional.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_lpv.h"

namespace canalid::core {

/// The model kinds with an online estimator, one registry for the daemon, `canalid replay` and
/// `canalid identify --online`.
enum class OnlineModelKind : std::uint8_t {
  kIntegratorDelay,  ///< "id": level against integrated flows, a bank over the delay
  kArx,              ///< "arx": actuator -> level, a bank over the delay
  kFractionalFoptd,  ///< "frac-foptd": K e^{-tau s} / (1 + T s^alpha), a bank over alpha
  kLpvArx,           ///< "lpv": ARX whose coefficients are quadratics in a scheduling variable
  /// "idz": the id bank with the wave front (p21 >= 0) and the outflow's direct gain p22 held at
  /// its prior (the theory's low-frequency p22): IDZ, whose area is right where the outflow
  /// follows the level (docs/closed-loop.md)
  kIdz,
  /// "frac-ss": the commensurate fractional state space (alpha = 1/q) at a known delay
  kFracSs,
};
inline constexpr std::array kOnlineModelKinds{
    OnlineModelKind::kIntegratorDelay, OnlineModelKind::kArx, OnlineModelKind::kFractionalFoptd,
    OnlineModelKind::kLpvArx,          OnlineModelKind::kIdz, OnlineModelKind::kFracSs};
/// The kind's name in configurations, CLI options, model JSON and LCM messages.
std::string_view OnlineModelKindName(OnlineModelKind kind);
std::optional<OnlineModelKind> OnlineModelKindFromName(std::string_view name);

/// One sample as a reach's online estimators see it, engineering units; NaN marks an invalid
/// value.  The integrator-delay model uses the flows and the level; the process models (arx,
/// frac-foptd, lpv, frac-ss) use `input` (the actuator: its measured position or its setpoint) and
/// the level as output, lpv also `scheduling`.
struct OnlineSample {
  double q_in_m3s = 0.0;
  double q_out_m3s = 0.0;
  double level_m = 0.0;
  double input = 0.0;
  double scheduling = 0.0;
};

/// What a user sets for the online estimators, in physical units, the same for every caller:
/// OnlineModelOptionsFor turns it into one kind's options (the only place seconds become
/// samples).  The daemon's configuration and `canalid identify --online` both fill it.
struct OnlineModelSettings {
  double sample_time_s = 1.0;  ///< Ts > 0
  // Every kind's recursive least squares.
  RlsMethod rls_method = RlsMethod::kUdDirectional;
  double forgetting = 1.0;  ///< (0, 1]
  /// P0 = p0 I, 0 < p0 <= 1e20; none: kDefaultInitialCovariance.
  std::optional<double> initial_covariance;
  // id and arx: the delays of the bank (rounded to whole samples).
  double min_delay_s = 0.0;
  double max_delay_s = 0.0;
  // id
  bool wave_front_term = false;  ///< OnlineIntegratorDelayOptions::wave_front_term (p21 >= 0)
  ClosedLoopMode closed_loop = ClosedLoopMode::kOff;
  double p22_s_per_m2 = 0.0;  ///< OnlineIntegratorDelayOptions::outflow_direct_gain_s_per_m2
  // idz: the id bank's settings above, with the wave front and this p22 prior held (s/m2, >= 0)
  double idz_p22_s_per_m2 = 0.0;
  // arx
  int arx_na = 2;
  int arx_nb = 2;
  // frac-foptd
  std::vector<double> fractional_alphas{0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4};
  double fractional_delay_s = 0.0;   ///< known delay (rounded to whole samples)
  double fractional_memory_s = 0.0;  ///< GL short memory (frac-foptd, frac-ss); 0: 200 samples
  // frac-ss
  int frac_ss_q = 2;             ///< alpha = 1/q, 1..4
  double frac_ss_delay_s = 0.0;  ///< known delay (rounded to whole samples)
  // lpv
  int lpv_na = 1;
  int lpv_nb = 1;
  double lpv_delay_s = 0.0;  ///< rounded to whole samples, >= 0
};

/// One kind's estimator options (only the member of `kind` is used).
struct OnlineModelOptions {
  OnlineModelKind kind = OnlineModelKind::kIntegratorDelay;
  double sample_time_s = 1.0;
  OnlineIntegratorDelayOptions id;
  OnlineArxOptions arx;
  OnlineFractionalOptions fractional;
  OnlineLpvArxOptions lpv;
  OnlineCommensurateOptions frac_ss;
  /// FLAG_ILL_CONDITIONED above it (the kinds other than id use RlsHealth's condition estimate).
  double condition_max = 1e12;

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// P0 = p0 I of every kind when the settings give none: 1e10, so that the prior weighs nothing
/// against the data (||theta||^2 / p0 against information of 1e2..1e9) and with forgetting 1 the
/// estimate is the batch least-squares fit of the same rows (to 1e-6 relative; at 1e6 the id
/// kind's p21 was 5e-6 off).  frac-foptd's rows are its candidates' simulated outputs.
inline constexpr double kDefaultInitialCovariance = 1e10;

/// The recursive least squares of an estimator with `num_params` parameters: the settings' method,
/// forgetting and P0 (constant trace holds the initial trace).
RlsOptions RlsOptionsFor(const OnlineModelSettings& settings, int num_params);

/// `kind`'s options from the settings: delays round(seconds / Ts); throws
/// std::invalid_argument naming the setting when the result is out of range.
OnlineModelOptions OnlineModelOptionsFor(OnlineModelKind kind, const OnlineModelSettings& settings);

/// The most parameters a snapshot carries (lpv: 3 (na + nb) coefficients, the delay and the
/// operating point).
inline constexpr int kMaxOnlineModelParams = 3 * kMaxOnlineArxParams + 3;

/// A model as published: named parameters with their standard deviations and the estimator's
/// health.  Fixed storage: filling one never allocates.  `names` points into the model that
/// filled it (valid while that model lives).
struct OnlineModelSnapshot {
  OnlineModelKind kind = OnlineModelKind::kIntegratorDelay;
  std::string_view estimator;  ///< "rls-bank" (a bank of candidates), "rls"
  bool valid = false;          ///< false until the estimator has an estimate
  std::int64_t samples_used = 0;
  int num_params = 0;
  std::span<const std::string> names;  ///< num_params names, with units ("delay_s", "area_m2")
  std::array<double, kMaxOnlineModelParams> values{};
  std::array<double, kMaxOnlineModelParams> std_devs{};  ///< 1 sigma; NaN when not known
  double trace_p = 0.0;
  double condition_number = 1.0;
  double excitation = 0.0;            ///< smallest eigenvalue of P^-1 where computed, else 0
  double prediction_error_rms = 0.0;  ///< innovation standard deviation, output units
  int flags = 0;                      ///< kFlag* bits

  /// The value of the parameter `name` (NaN when absent).
  double Value(std::string_view name) const;
};

/// One online estimator of one kind on a reach's samples.  Implementations allocate only in
/// their constructor; Update and FillSnapshot never allocate.  Deterministic.
class OnlineModel {
 public:
  virtual ~OnlineModel() = default;
  OnlineModel() = default;
  OnlineModel(const OnlineModel&) = delete;
  OnlineModel& operator=(const OnlineModel&) = delete;

  virtual OnlineModelKind kind() const = 0;
  /// One sample.  Returns true when the estimate moved (worth publishing).
  virtual bool Update(const OnlineSample& sample) = 0;
  virtual void FillSnapshot(OnlineModelSnapshot& out) const = 0;
  /// Restarts from the initial state (an operator's reset).
  virtual void Reset() = 0;
  /// The integrator-delay bank behind the id kind (nullptr for the other kinds).
  virtual const OnlineIntegratorDelayBank* integrator_delay_bank() const { return nullptr; }
};

/// The estimator of `options.kind`.  @throws std::invalid_argument on bad options.
std::unique_ptr<OnlineModel> MakeOnlineModel(const OnlineModelOptions& options);

}  // namespace canalid::core
