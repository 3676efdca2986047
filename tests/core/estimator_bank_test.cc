// BankSelector's two criteria on hand-written loss sequences.
#include "core/online/estimator_bank.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace canalid::core {
namespace {

BankSelectorOptions Residual(int warmup) {
  BankSelectorOptions o;
  o.criterion = BankCriterion::kResidual;
  o.warmup_samples = warmup;
  return o;
}

// kResidual takes the smallest loss on every sample after the warm-up: a lead of 0.1 %, which the
// prediction-error criterion's 10 % margin would ignore, is enough, and the choice follows the
// losses back at once.
TEST(BankSelector, ResidualTakesTheSmallestLossOnEverySample) {
  BankSelector s(3, Residual(2));
  const double losses[][3] = {{1.0, 2.0, 3.0},   {3.0, 2.0, 1.0},   {1.0, 1.001, 2.0},
                              {1.001, 1.0, 2.0}, {1.0, 1.001, 2.0}, {5.0, 5.0, 5.0}};
  const int expected[] = {-1, -1, 0, 1, 0, 0};  // ties: the first candidate
  for (int k = 0; k < 6; ++k) {
    for (int i = 0; i < 3; ++i) s.SetLoss(i, losses[k][i]);
    EXPECT_EQ(s.Commit(), expected[k]) << "sample " << k;
  }
  EXPECT_EQ(s.switches(), 2);
}

TEST(BankSelector, ResidualNeverChoosesANonFiniteLoss) {
  BankSelector s(2, Residual(0));
  s.SetLoss(0, std::numeric_limits<double>::quiet_NaN());
  s.SetLoss(1, 1e9);
  EXPECT_EQ(s.Commit(), 1);
  s.SetLoss(0, 1.0);
  s.SetLoss(1, std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.Commit(), 0);
  // No finite loss at all: the choice stays (here candidate 0), and a fresh bank chooses none.
  s.SetLoss(0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(s.Commit(), 0);
  BankSelector fresh(2, Residual(0));
  fresh.SetLoss(0, std::numeric_limits<double>::infinity());
  fresh.SetLoss(1, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(fresh.Commit(), -1);
}

// The choice is the first smallest finite loss, for every bank size (whole runs of eight, pairs
// and a last odd one), with ties (zeros of both signs among them), NaNs and infinities of both
// signs among the losses.  The reference is the plain one-pass search.
TEST(BankSelector, ResidualChoosesTheFirstSmallestFiniteLossAtEverySize) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double pool[] = {3.0, 1.0, 2.0, 1.0, nan, inf, -inf, 0.5, 0.5, 7.0, 0.0, -0.0};
  std::uint64_t state = 12345;
  for (int n = 1; n <= 27; ++n) {
    for (int trial = 0; trial < 300; ++trial) {
      BankSelector s(n, Residual(0));
      int expected = -1;
      double smallest = inf;
      for (int i = 0; i < n; ++i) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        const double l = pool[(state >> 33) % std::size(pool)];
        s.SetLoss(i, l);
        if (std::isfinite(l) && l < smallest) {
          smallest = l;
          expected = i;
        }
      }
      EXPECT_EQ(s.Commit(), expected) << "n " << n << " trial " << trial;
    }
  }
}

// kPredictionError: a challenger must beat the selected candidate by the margin on
// switch_hold_samples consecutive samples.
TEST(BankSelector, PredictionErrorSwitchesOnlyAfterTheHold) {
  BankSelectorOptions o;
  o.warmup_samples = 0;
  o.switch_margin = 0.1;
  o.switch_hold_samples = 3;
  o.loss_forgetting = 0.5;
  BankSelector s(2, o);
  s.Record(0, 1.0);
  s.Record(1, 2.0);
  EXPECT_EQ(s.Commit(), 0);
  int switched_at = -1;
  for (int k = 1; k <= 10 && switched_at < 0; ++k) {
    s.Record(0, 2.0);
    s.Record(1, 0.1);
    if (s.Commit() == 1) switched_at = k;
  }
  // Losses after k samples: J0 = 4 - 3 / 2^k, J1 = 0.01 + 3.99 / 2^k; J1 < 0.9 J0 from k = 1 on,
  // so the third consecutive sample switches.
  EXPECT_EQ(switched_at, 3);
  EXPECT_EQ(s.switches(), 1);
}

TEST(BankSelector, BadOptionsThrow) {
  BankSelectorOptions o;
  o.loss_forgetting = 1.0;
  EXPECT_THROW(BankSelector(2, o), std::invalid_argument);
  EXPECT_THROW(BankSelector(0, BankSelectorOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
