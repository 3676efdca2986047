#include "core/online/estimator_bank.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

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
  // Without a branch per candidate (losses close to each other make such branches
  // unpredictable: they cost more than the comparisons), and in four chains of comparisons
  // (candidates i = c mod 4) rather than one: each chain's first smallest, then the smallest of
  // those, the first on a tie.  A NaN compares false, so it is never smallest; nor is an infinity.
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const std::size_t n = loss_.size();
  struct Chain {
    std::size_t best;
    double loss = kInfinity;
    void Take(double l, std::size_t i) {
      const bool less = (l < loss) & (l > -kInfinity);
      best = less ? i : best;
      loss = less ? l : loss;
    }
  };
  Chain c0{n}, c1{n}, c2{n}, c3{n};  // best = n: none yet
  const double* l = loss_.data();
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    c0.Take(l[i], i);
    c1.Take(l[i + 1], i + 1);
    c2.Take(l[i + 2], i + 2);
    c3.Take(l[i + 3], i + 3);
  }
  if (i < n) c0.Take(l[i], i);
  if (i + 1 < n) c1.Take(l[i + 1], i + 1);
  if (i + 2 < n) c2.Take(l[i + 2], i + 2);
  Chain best = c0;
  for (const Chain& c : {c1, c2, c3}) {
    if (c.loss < best.loss || (c.loss == best.loss && c.best < best.best)) best = c;
  }
  return best.best == n ? 0 : static_cast<int>(best.best);
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
