#pragma once
#include <cstdint>
#include <vector>

#include "core/estimator_bank.h"
#include "core/ring_buffer.h"
#include "core/rls.h"
#include "core/rls_iv.h"

namespace canalid::core {

/// Options of OnlineIdBank.
struct OnlineIdOptions {
  double sample_time_s = 1.0;  ///< Ts > 0
  int min_delay_samples = 0;   ///< smallest candidate nk >= 0
  int max_delay_samples = 0;   ///< largest candidate nk >= min_delay_samples
  RlsOptions rls;              ///< per candidate (n = 3); the default UD method, lambda 1
  BankSelectorOptions selector;
  /// Re-centring period of the regressor (samples): 0 = automatic, i.e. never for lambda = 1 and
  /// ceil(1 / (1 - lambda)) (one memory length) otherwise; < 0 = never.
  int recentre_samples = 0;
  /// Closed loop (a downstream gate whose outflow follows the level): each candidate is fitted by
  /// instrumental-variable RLS (IvRls) with the instrument z = [Qin_nk(k), 1, k - k0],
  /// Qin_nk(k) = sum_{j=k0..k} (q_in(j - nk) - q_ref), q_ref the first good inflow.  The inflow
  /// is the excitation and does not see the level noise; q_ref only keeps the numbers small
  /// (z spans 1 and k - k0, so any linear trend removed from Qin leaves the estimate unchanged).
  /// Limitation (measured in online_id_closed_loop_test): a persistent unmeasured disturbance
  /// (an offtake stepping slowly) integrates into a random walk in the level equation that neither
  /// this IV nor least squares on the integrated form can separate from Q (spurious regression:
  /// area off by 2-10x); use the batch three-step method for such data.
  bool closed_loop_iv = false;
  double flow_abs_max_m3s = 1e5;  ///< |q| above it (or non-finite) is an absurd flow
  double level_abs_max_m = 1e4;   ///< |y| above it (or non-finite) is an absurd level

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// One candidate's (or the selected) integrator-delay model.
struct IdSnapshot {
  bool valid = false;        ///< false until the first regression sample
  std::int64_t sample = -1;  ///< index k of the last sample (0 = first sample given)
  int delay_samples = -1;    ///< nk
  double delay_s = 0.0;      ///< nk Ts
  double b = 0.0;            ///< backwater coefficient (s/m^2 per sample): level per m^3/s x sample
  double c_m = 0.0;          ///< offset at k = k0
  double d_m = 0.0;          ///< drift per sample
  double area_m2 = 0.0;      ///< Ts / b
  double b_std = 0.0;        ///< standard deviations from sigma2 P
  double c_std_m = 0.0;
  double d_std_m = 0.0;
  double area_std_m2 = 0.0;         ///< Ts b_std / b^2 (first order)
  double prediction_error_m = 0.0;  ///< last a-priori error
  double innovation_std_m = 0.0;    ///< sqrt(sigma2)
  double loss = 0.0;                ///< the selector's weighted squared a-priori error
  RlsHealth health;
};

/// Bank health beyond the per-estimator RlsHealth.
struct IdBankHealth {
  std::int64_t samples = 0;            ///< samples accepted into the time base
  std::int64_t bad_flow_samples = 0;   ///< flows replaced by the last good ones
  std::int64_t bad_level_samples = 0;  ///< no regression update on these samples
  std::int64_t dropped_samples = 0;    ///< bad flows before any good one: not used at all
  int switches = 0;                    ///< delay changes made by the selector
};

/// Online integrator-delay (ID) identification of a canal pool with a bank over the delay nk.
/// For the samples k = 0, 1, ... of inflow q_in (m^3/s), outflow q_out (m^3/s) and level y (m):
///   v_nk(k) = q_in(k - nk) - q_out(k - 1),   Q_nk(k) = sum_{j=k0..k} v_nk(j)  (m^3/s x samples),
///   y(k) = b Q_nk(k) + c + d (k - k0),       k0 = max_delay_samples + 1,
/// i.e. the level against the integrated total flow with an offset and a drift (the low-frequency
/// form of y(k) - y(k-1) = b (q_in(k - nk) - q_out(k - 1))), fitted by one Rls<3> per candidate
/// from k = k0 on.  With lambda = 1 and a large P0 each candidate equals batch least squares on the
/// rows phi = [Q_nk(k), 1, k - k0], k = k0..K.  area_m2 = Ts / b, delay_s = nk Ts.
///
/// Forgetting < 1: Q_nk and k - k0 grow without bound while the memory does not, so the
/// regressor is re-centred every recentre_samples: internally phi = [Q - Q_c, 1, (k - k0) - t_c]
/// and theta = [b, c + b Q_c + d t_c, d], changed exactly by Rls::Transform at each new centre;
/// snapshots always report c and d in the batch convention above.
///
/// A non-finite or absurd flow is replaced by the last good value of that flow (so the
/// integrators stay continuous) and counted; a bad level skips the regression update for that
/// sample.  The selector (BankSelector) picks nk by the weighted a-priori error with hysteresis.
/// Allocates only in the constructor; Update and the snapshots never allocate.  Deterministic.
class OnlineIdBank final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineIdBank(const OnlineIdOptions& options);

  /// One sample.  Returns true when the candidates were updated (k >= k0 and a good level).
  bool Update(double q_in_m3s, double q_out_m3s, double level_m);

  /// The selected candidate (valid = false before the selector's first choice).
  IdSnapshot Snapshot() const;
  /// Candidate with delay nk.  @pre min_delay_samples <= nk <= max_delay_samples.
  IdSnapshot CandidateSnapshot(int delay_samples) const;
  int selected_delay_samples() const;
  int num_candidates() const { return static_cast<int>(q_integrated_.size()); }
  const IdBankHealth& health() const { return health_; }
  const OnlineIdOptions& options() const { return options_; }

 private:
  void Recentre();
  template <typename Estimator>
  IdSnapshot MakeSnapshot(const Estimator& rls, int i) const;

  OnlineIdOptions options_;
  std::vector<Rls<3>> estimators_;       // open loop
  std::vector<IvRls<3>> iv_estimators_;  // closed loop
  std::vector<double> qin_integrated_;   // instrument Qin_nk(k)
  std::vector<double> qin_centre_;
  double q_ref_ = 0.0;
  std::vector<double> q_integrated_;  // Q_nk(k)
  std::vector<double> q_centre_;      // Q_c per candidate
  BankSelector selector_;
  RingBuffer<double> q_in_history_;
  double q_in_good_ = 0.0;
  double q_out_good_ = 0.0;
  double q_out_previous_ = 0.0;
  bool have_good_ = false;
  std::int64_t k_ = -1;
  std::int64_t k0_ = 0;
  double t_centre_ = 0.0;
  int recentre_period_ = 0;
  IdBankHealth health_;
};

}  // namespace canalid::core
