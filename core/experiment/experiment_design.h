#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace canalid::core {

/// What the designer needs to know about the pool (docs/references.md).
struct ExperimentDesignRequest {
  double nominal_flow_m3s = 0.0;   ///< inflow around which the PRBS switches, > 0
  double expected_delay_s = 0.0;   ///< operators' delay guess (largest time constant), > 0
  double sample_time_s = 0.0;      ///< > 0
  double amplitude_percent = 7.5;  ///< PRBS amplitude in % of nominal flow, 5..10
  double duration_factor = 5.0;    ///< minimum duration in multiples of the delay, 5..20
  int max_order = 16;              ///< largest LFSR order tried before repeating periods, 2..31
  /// @throws std::invalid_argument naming the field, its value and the allowed range.
  void Validate() const;
};

/// A PRBS experiment on the inflow: levels nominal +- amplitude_m3s, each bit held for
/// clock_period_samples samples, num_periods periods of an order-`order` m-sequence.
struct ExperimentDesign {
  double amplitude_m3s = 0.0;
  int clock_period_samples = 1;
  double clock_period_s = 0.0;  ///< clock_period_samples * sample_time_s
  int order = 2;
  int num_periods = 1;
  Eigen::Index num_samples = 0;  ///< num_periods * (2^order - 1) * clock_period_samples
  double duration_s = 0.0;       ///< num_samples * sample_time_s
  /// One sentence per rule applied, with the numbers, for the operator.
  std::vector<std::string> explanation;
};

/// Designs the experiment with these rules:
///   amplitude      = amplitude_percent / 100 * nominal_flow_m3s;
///   clock period   = round(expected_delay_s / 2 / sample_time_s) samples, at least 1 sample
///                    (about half the delay, never shorter than a sample);
///   required       = duration_factor * expected_delay_s;
///   order          = the smallest n in [2, max_order] with (2^n - 1) clock periods >= required;
///   num_periods    = 1 if such an n exists, else ceil(required / one period of order max_order).
/// @throws std::invalid_argument if the request is invalid.
ExperimentDesign DesignPrbsExperiment(const ExperimentDesignRequest& request);

}  // namespace canalid::core
