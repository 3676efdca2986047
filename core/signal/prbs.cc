#include "core/signal/prbs.h"

#include <array>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {
namespace {

// XAPP052 table 3 (taps for XNOR/XOR Fibonacci LFSRs); index = order.  Order 2 is x^2 + x + 1.
constexpr std::array<std::array<int, 4>, kMaxLfsrOrder + 1> kTaps = {{
    {0, 0, 0, 0},   {0, 0, 0, 0},    {2, 1, 0, 0},   {3, 2, 0, 0},   {4, 3, 0, 0},
    {5, 3, 0, 0},   {6, 5, 0, 0},    {7, 6, 0, 0},   {8, 6, 5, 4},   {9, 5, 0, 0},
    {10, 7, 0, 0},  {11, 9, 0, 0},   {12, 6, 4, 1},  {13, 4, 3, 1},  {14, 5, 3, 1},
    {15, 14, 0, 0}, {16, 15, 13, 4}, {17, 14, 0, 0}, {18, 11, 0, 0}, {19, 6, 2, 1},
    {20, 17, 0, 0}, {21, 19, 0, 0},  {22, 21, 0, 0}, {23, 18, 0, 0}, {24, 23, 22, 17},
    {25, 22, 0, 0}, {26, 6, 2, 1},   {27, 5, 2, 1},  {28, 25, 0, 0}, {29, 27, 0, 0},
    {30, 6, 4, 1},  {31, 28, 0, 0},
}};

void CheckOrder(int order) {
  if (order < kMinLfsrOrder || order > kMaxLfsrOrder) {
    throw std::invalid_argument("LFSR order " + std::to_string(order) + " is outside [" +
                                std::to_string(kMinLfsrOrder) + ", " +
                                std::to_string(kMaxLfsrOrder) + "]");
  }
}

}  // namespace

std::span<const int> LfsrTaps(int order) {
  CheckOrder(order);
  const auto& row = kTaps[static_cast<std::size_t>(order)];
  std::size_t count = 0;
  while (count < row.size() && row[count] != 0) ++count;
  return {row.data(), count};
}

MaximalLengthSequence::MaximalLengthSequence(int order, std::uint32_t seed)
    : order_(order), tap_mask_(0), state_mask_(0), state_(0) {
  CheckOrder(order);
  state_mask_ = static_cast<std::uint32_t>((std::uint64_t{1} << order) - 1);
  // Tap k reads a(t-k), which sits in bit k-1 of the register.
  for (int tap : LfsrTaps(order)) tap_mask_ |= std::uint32_t{1} << (tap - 1);
  state_ = seed & state_mask_;
  if (state_ == 0 || state_ != seed) {
    throw std::invalid_argument("MaximalLengthSequence: seed " + std::to_string(seed) +
                                " must be nonzero and fit in " + std::to_string(order) + " bits");
  }
}

int MaximalLengthSequence::Next() {
  const std::uint32_t bit = static_cast<std::uint32_t>(std::popcount(state_ & tap_mask_)) & 1U;
  state_ = ((state_ << 1) | bit) & state_mask_;
  return bit != 0 ? 1 : -1;
}

void PrbsSignalSpec::Validate() const {
  if (!(amplitude > 0.0) || !std::isfinite(amplitude)) {
    throw std::invalid_argument("PrbsSignalSpec.amplitude " + std::to_string(amplitude) +
                                " must be finite and > 0");
  }
  if (!std::isfinite(nominal)) {
    throw std::invalid_argument("PrbsSignalSpec.nominal must be finite");
  }
  if (clock_period_samples < 1) {
    throw std::invalid_argument("PrbsSignalSpec.clock_period_samples " +
                                std::to_string(clock_period_samples) + " must be >= 1");
  }
  // Constructing the sequence validates order and seed with their own messages.
  MaximalLengthSequence check(order, seed);
}

PrbsGenerator::PrbsGenerator(const PrbsSignalSpec& spec)
    : spec_(spec), sequence_((spec.Validate(), spec.order), spec.seed) {}

double PrbsGenerator::Next() {
  if (samples_left_in_clock_ == 0) {
    held_value_ = sequence_.Next();
    samples_left_in_clock_ = spec_.clock_period_samples;
  }
  --samples_left_in_clock_;
  if (spec_.integrate) {
    sum_ += held_value_;
    return spec_.nominal + spec_.amplitude * sum_;
  }
  return spec_.nominal + spec_.amplitude * held_value_;
}

std::int64_t PrbsGenerator::period_samples() const {
  return sequence_.period() * spec_.clock_period_samples;
}

Eigen::VectorXd GeneratePrbs(const PrbsSignalSpec& spec, Eigen::Index num_samples) {
  if (num_samples < 0) {
    throw std::invalid_argument("GeneratePrbs: num_samples " + std::to_string(num_samples) +
                                " must be >= 0");
  }
  PrbsGenerator generator(spec);
  Eigen::VectorXd u(num_samples);
  for (Eigen::Index k = 0; k < num_samples; ++k) u(k) = generator.Next();
  return u;
}

}  // namespace canalid::core
