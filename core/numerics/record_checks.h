#pragma once
#include <Eigen/Core>
#include <string_view>

namespace canalid::core {

/// The length check of an input/output record before a fit.
/// @throws std::invalid_argument "<where>: input has N samples but output has M" when the lengths
///   differ, and "<where>: N samples, need at least MIN" when there are fewer than `min_samples`.
void CheckRecordLengths(std::string_view where, Eigen::Index input_size, Eigen::Index output_size,
                        Eigen::Index min_samples);

}  // namespace canalid::core
