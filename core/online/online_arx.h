#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string_view>

#include "core/numerics/ring_buffer.h"
#include "core/online/arx_candidates.h"
#include "core/online/estimator_bank.h"
#include "core/online/rls.h"

namespace canalid::core {

/// The ARX orders of an online estimator's options: na >= 0, nb >= 1, na + nb <=
/// kMaxOnlineArxParams.  @throws std::invalid_argument "<owner>.<name> = ..."
/// (ThrowOptionOutOfRange).
void CheckOnlineArxOrders(std::string_view owner, int na, int nb);

struct OnlineArxOptions {
  int na = 2;                 ///< >= 0
  int nb = 2;                 ///< >= 1, na + nb <= kMaxOnlineArxParams
  int min_delay_samples = 1;  ///< >= 0
  int max_delay_samples = 1;  ///< >= min_delay_samples
  RlsOptions rls;             ///< per candidate (n = na + nb)
  /// The delay's choice.  Default kResidual: the candidate of smallest least-squares loss, so
  /// that with lambda = 1 the bank's nk is a batch scan's over the same rows (a candidate skips
  /// the rows a bad u enters, so its loss then covers a few rows fewer; nb rows per bad u).
  BankSelectorOptions selector{.criterion = BankCriterion::kResidual};
  double input_abs_max = 1e9;   ///< |u| above it (or non-finite) is absurd
  double output_abs_max = 1e9;  ///< |y| above it (or non-finite) is absurd

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

struct ArxSnapshot {
  bool valid = false;
  std::int64_t sample = -1;
  int delay_samples = -1;
  ArxParamVector a;      ///< a1..a_na (MATLAB sign convention)
  ArxParamVector b;      ///< b1..b_nb
  ArxParamVector a_std;  ///< standard deviations from sigma2 P
  ArxParamVector b_std;
  double prediction_error = 0.0;
  double innovation_std = 0.0;
  double loss = 0.0;
  RlsHealth health;
};

struct ArxBankHealth {
  std::int64_t samples = 0;
  std::int64_t bad_inputs = 0;   ///< the regressions that would contain them are skipped
  std::int64_t bad_outputs = 0;  ///< ditto
  int switches = 0;
};

/// Online ARX  y(k) + a1 y(k-1) + ... + a_na y(k-na) = b1 u(k-nk) + ... + b_nb u(k-nk-nb+1) + e(k)
/// (MATLAB's convention) with one estimator per candidate nk (ArxCandidates: RlsBank lanes up to
/// n = 8 parameters) and a BankSelector choosing nk.
/// Regressor phi(k) = [-y(k-1) .. -y(k-na), u(k-nk) .. u(k-nk-nb+1)], used from
/// k = k_start = max(na, max_delay_samples + nb - 1) on (the same rows for every candidate), so
/// with lambda = 1 and a large P0 each candidate equals batch least squares on those rows.
/// A non-finite or absurd u or y is never used: every regression containing it is skipped (the
/// bad value is kept out of the state: a candidate's estimator rejects a row with a bad input,
/// counted in its health.rejected_invalid; a bad output skips the sample for all).
/// Allocates only in the constructor.  Deterministic.  Not thread-safe, its const members
/// included (a snapshot reads a lane through RlsBank's scratch estimator).
class OnlineArxBank final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineArxBank(const OnlineArxOptions& options);

  /// One sample of input u(k) and output y(k).  Returns true when the candidates were updated.
  bool Update(double u, double y);

  ArxSnapshot Snapshot() const;
  ArxSnapshot CandidateSnapshot(int delay_samples) const;
  int selected_delay_samples() const;
  const ArxBankHealth& health() const { return health_; }

 private:
  OnlineArxOptions options_;
  int n_;
  std::unique_ptr<ArxCandidates> candidates_;
  BankSelector selector_;
  RingBuffer<double> u_history_;
  RingBuffer<std::uint8_t> u_bad_history_;  // 1 where u_history_ holds a bad input's placeholder
  RingBuffer<double> y_history_;
  std::array<double, kMaxOnlineArxParams> minus_y_lags_{};
  std::int64_t k_ = -1;
  std::int64_t k_start_ = 0;
  std::int64_t last_bad_y_ = -1000000000;
  ArxBankHealth health_;
};

}  // namespace canalid::core
