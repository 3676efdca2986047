#pragma once
#include <Eigen/Core>
#include <array>

namespace canalid::core {

/// First order plus time delay: G(s) = K e^{-tau s} / (1 + T s).
struct FoptdModel {
  double gain = 1.0;             ///< K, output units per input unit
  double time_constant_s = 1.0;  ///< T > 0
  double delay_s = 0.0;          ///< tau >= 0, any real value (sub-sample)
};

/// Second order plus time delay: G(s) = K e^{-tau s} / ((1 + T1 s)(1 + T2 s)), T1 >= T2 > 0.
struct SoptdModel {
  double gain = 1.0;
  std::array<double, 2> time_constants_s{1.0, 1.0};
  double delay_s = 0.0;
};

/// Responses from rest to an input held constant over each sample (exact ZOH, sub-sample delay
/// included, see DelayedZoh).  `u` and the result are deviations from the initial steady state.
/// @throws std::invalid_argument for non-positive time constants, a negative delay, Ts <= 0 or a
///         delay longer than kMaxDelaySamples (1e7) samples.
Eigen::VectorXd Simulate(const FoptdModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         double sample_time_s);
Eigen::VectorXd Simulate(const SoptdModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         double sample_time_s);

}  // namespace canalid::core
