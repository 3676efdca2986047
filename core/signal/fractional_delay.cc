#include "core/signal/fractional_delay.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {

ZohDelaySplit SplitZohDelay(double delay_s, double sample_time_s) {
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
    throw std::invalid_argument("SplitZohDelay: sample_time_s = " + std::to_string(sample_time_s) +
                                " must be > 0");
  }
  if (!(delay_s >= 0.0) || !std::isfinite(delay_s) || delay_s / sample_time_s > kMaxDelaySamples) {
    throw std::invalid_argument("SplitZohDelay: delay_s = " + std::to_string(delay_s) +
                                " must be in [0, 1e7 sample times]");
  }
  const double samples = delay_s / sample_time_s;
  ZohDelaySplit split;
  split.whole_samples = static_cast<int>(std::floor(samples));
  split.fraction = samples - split.whole_samples;
  // A delay a rounding error short of a whole number of samples is that whole number.
  if (split.fraction > 1.0 - 1e-12) {
    ++split.whole_samples;
    split.fraction = 0.0;
  }
  return split;
}

namespace {
int CheckedSize(int whole_samples) {
  if (whole_samples < 0) {
    throw std::invalid_argument("ZohDelayLine: whole_samples = " + std::to_string(whole_samples) +
                                " must be >= 0");
  }
  return whole_samples + 2;
}
}  // namespace

ZohDelayLine::ZohDelayLine(int whole_samples)
    : buffer_(Eigen::VectorXd::Zero(CheckedSize(whole_samples))), size_(whole_samples + 2) {}

}  // namespace canalid::core
