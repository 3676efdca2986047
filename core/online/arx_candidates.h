#pragma once
// The candidate estimators of an online ARX delay bank, updated together.
#include <cstdint>
#include <memory>

#include <Eigen/Core>

#include "core/numerics/ring_buffer.h"
#include "core/online/estimator_bank.h"
#include "core/online/rls.h"

namespace canalid::core {

/// Largest na + nb of the online ARX estimators (snapshots use fixed-capacity storage).
inline constexpr int kMaxOnlineArxParams = 16;
/// A vector of at most kMaxOnlineArxParams values stored inline (no heap).
using ArxParamVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxOnlineArxParams, 1>;

/// One sample's regression rows, one per candidate delay nk = min_delay + c:
///   phi_c = [-y(k-1) .. -y(k-na), u(k-nk) .. u(k-nk-nb+1)].
struct ArxRows {
  int na = 0;
  int nb = 1;
  int min_delay = 0;
  const double* minus_y_lags = nullptr;             ///< -y(k-1) .. -y(k-na)
  const RingBuffer<double>* u = nullptr;            ///< u(k - j) at [j]
  const RingBuffer<std::uint8_t>* u_bad = nullptr;  ///< 1 where u holds a bad input's placeholder
};

/// What a snapshot reads of one candidate.
struct ArxCandidateState {
  ArxParamVector theta;
  ArxParamVector std_dev;  ///< sqrt(sigma2 P_ii)
  double innovation_variance = 0.0;
  double last_prediction_error = 0.0;
  RlsHealth health;
};

/// `count` estimators of n = na + nb parameters with the same options.  Up to
/// kMaxArxLaneParams parameters they are the lanes of an RlsBank<n> (one structure-of-arrays
/// update for all, each lane bit for bit an Rls<n>); above, one Rls<Dynamic> each.  A row that
/// reads a bad input is given to its estimator as non-finite, which rejects it (counted in
/// health.rejected_invalid) and leaves the estimate and its loss as they were.  Allocates only
/// when made.  Deterministic.  Not thread-safe (RlsBank::Lane).
class ArxCandidates {
 public:
  /// Largest n run as RlsBank lanes (the sizes instantiated; ARX(2, 2) is 4).
  static constexpr int kMaxArxLaneParams = 8;

  virtual ~ArxCandidates() = default;
  /// @throws std::invalid_argument on a bad option (RlsOptions::Validate).
  static std::unique_ptr<ArxCandidates> Make(const RlsOptions& options, int num_params, int count);

  /// Updates every candidate with its row of `rows` and output y, then gives the selector each
  /// candidate's loss (kResidual) or a-priori error (otherwise).
  virtual void Update(const ArxRows& rows, double y, BankSelector& selector) = 0;
  /// Candidate c's estimate and health.
  virtual void State(int c, ArxCandidateState& out) const = 0;
  /// Whether the candidates run as structure-of-arrays lanes.
  virtual bool lanes() const = 0;
};

}  // namespace canalid::core
