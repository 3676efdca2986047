#include "core/numerics/record_checks.h"

#include <stdexcept>
#include <string>

namespace canalid::core {

void CheckRecordLengths(std::string_view where, Eigen::Index input_size, Eigen::Index output_size,
                        Eigen::Index min_samples) {
  const std::string w(where);
  if (output_size != input_size) {
    throw std::invalid_argument(w + ": input has " + std::to_string(input_size) +
                                " samples but output has " + std::to_string(output_size));
  }
  if (input_size < min_samples) {
    throw std::invalid_argument(w + ": " + std::to_string(input_size) + " samples, need at least " +
                                std::to_string(min_samples));
  }
}

}  // namespace canalid::core
