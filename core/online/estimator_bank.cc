#include "core/online/estimator_bank.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/numerics/lane_vectors.h"

namespace canalid::core {

void BankSelectorOptions::Validate() const {
  std::ostringstream m;
  if (!(loss_forgetting > 0.0 && loss_forgetting < 1.0)) {
    m << "BankSelectorOptions.loss_forgetting = " << loss_forgetting << " (allowed: 0 < . < 1)";
  } else if (!(switch_margin >= 0.0 && switch_margin < 1.0)) {
    m << "BankSelectorOptions.switch_margin = " << switch_margin << " (allowed: 0 <= . < 1)";
  } else if (switch_hold_samples < 1) {
    m << "BankSelectorOptions.switch_hold_samples = " << switch_hold_samples << " (allowed: >= 1)";
  } else if (warmup_samples < 0) {
    m << "BankSelectorOptions.warmup_samples = " << warmup_samples << " (allowed: >= 0)";
  } else {
    return;
  }
  throw std::invalid_argument(m.str());
}

BankSelector::BankSelector(int num_candidates, const BankSelectorOptions& options)
    : options_(options) {
  options_.Validate();
  if (num_candidates < 1) {
    throw std::invalid_argument("BankSelector: num_candidates = " + std::to_string(num_candidates) +
                                " (allowed: >= 1)");
  }
  loss_.assign(static_cast<std::size_t>(num_candidates), 0.0);
}

void BankSelector::Reset() {
  for (double& l : loss_) l = 0.0;
  samples_ = 0;
  selected_ = -1;
  challenger_ = -1;
  challenger_count_ = 0;
  switches_ = 0;
}

void BankSelector::Record(int i, double prediction_error) {
  // The warm-up errors (estimators still converging from theta = 0) would dominate the average
  // for many memory lengths: they are not recorded.
  if (!std::isfinite(prediction_error) || samples_ < options_.warmup_samples) return;
  double& l = loss_[static_cast<std::size_t>(i)];
  // Start the average at the first error so that early samples are not weighted toward zero.
  l = samples_ == options_.warmup_samples
          ? prediction_error * prediction_error
          : options_.loss_forgetting * l +
                (1.0 - options_.loss_forgetting) * prediction_error * prediction_error;
}

int BankSelector::FirstSmallest() const {
  // Two passes.  The smallest finite loss, without a branch per candidate (losses close to each
  // other make such branches unpredictable): vector minimums, two candidates per SSE2 operation
  // and four independent chains of them.  Then the first candidate holding it: that branch is
  // taken where the selection is, which rarely moves.  A non-finite loss is never smallest: it
  // enters the minimum as +infinity, and none equals a finite minimum.
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const double* l = loss_.data();
  const std::size_t n = loss_.size();
  const DoublePair infinite = {kInfinity, kInfinity};
  const auto take = [&infinite](DoublePair smallest, const double* at) {
    DoublePair x = LoadPair(at);
    x = (x - x == 0.0) ? x : infinite;  // x - x is 0 exactly when x is finite
    return x < smallest ? x : smallest;
  };
  DoublePair m0 = infinite, m1 = infinite, m2 = infinite, m3 = infinite;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    m0 = take(m0, l + i);
    m1 = take(m1, l + i + 2);
    m2 = take(m2, l + i + 4);
    m3 = take(m3, l + i + 6);
  }
  for (; i + 2 <= n; i += 2) m0 = take(m0, l + i);
  m0 = m0 < m1 ? m0 : m1;
  m2 = m2 < m3 ? m2 : m3;
  m0 = m0 < m2 ? m0 : m2;
  double smallest = m0[0] < m0[1] ? m0[0] : m0[1];
  if (i < n && std::isfinite(l[i]) && l[i] < smallest) smallest = l[i];
  if (smallest == kInfinity) return 0;  // none is finite
  std::size_t first = 0;
  while (l[first] != smallest) ++first;
  return static_cast<int>(first);
}

int BankSelector::Commit() {
  ++samples_;
  if (samples_ <= options_.warmup_samples) return selected_;
  const int best = FirstSmallest();
  if (options_.criterion == BankCriterion::kResidual) {
    if (!std::isfinite(loss(best))) return selected_;  // no candidate has a loss yet
    if (selected_ >= 0 && best != selected_) ++switches_;
    selected_ = best;
    return selected_;
  }
  if (selected_ < 0) {
    selected_ = best;
    return selected_;
  }
  if (best != selected_ && loss(best) < (1.0 - options_.switch_margin) * loss(selected_)) {
    if (best == challenger_) {
      ++challenger_count_;
    } else {
      challenger_ = best;
      challenger_count_ = 1;
    }
    if (challenger_count_ >= options_.switch_hold_samples) {
      selected_ = best;
      challenger_ = -1;
      challenger_count_ = 0;
      ++switches_;
    }
  } else {
    challenger_ = -1;
    challenger_count_ = 0;
  }
  return selected_;
}

}  // namespace canalid::core
