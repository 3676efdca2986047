// FitArxOverDelays (the daemon's batch arx) against the scan it replaced: one FitArx per
// candidate delay on the same equations, the smallest loss kept.
#include "core/linear/arx_delay_scan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/signal/prbs.h"

namespace canalid::core {
namespace {

// y(t) - 1.5 y(t-1) + 0.56 y(t-2) = 0.04 u(t-nk) + 0.02 u(t-nk-1) + e(t), u a PRBS.
void MakeRecord(int n, int nk, double noise_std, Eigen::VectorXd& y, Eigen::VectorXd& u) {
  PrbsSignalSpec spec;
  spec.amplitude = 1.0;
  spec.clock_period_samples = 5;
  spec.order = 9;
  u = GeneratePrbs(spec, n);
  y = Eigen::VectorXd::Zero(n);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, noise_std);
  auto at = [](const Eigen::VectorXd& v, int t) { return t >= 0 ? v(t) : 0.0; };
  for (int t = 0; t < n; ++t) {
    y(t) = 1.5 * at(y, t - 1) - 0.56 * at(y, t - 2) + 0.04 * at(u, t - nk) +
           0.02 * at(u, t - nk - 1) + normal(rng);
  }
}

// The reference: every candidate fitted in full by FitArx from the first equation the largest
// delay allows.
ArxModel EveryCandidateFitted(const Eigen::VectorXd& y, const Eigen::VectorXd& u, int na, int nb,
                              int min_nk, int max_nk) {
  ArxOrders orders;
  orders.na = na;
  orders.nb = {nb};
  orders.nk = {max_nk};
  const Eigen::Index first = orders.min_first_sample();
  std::optional<ArxModel> best;
  for (int nk = min_nk; nk <= max_nk; ++nk) {
    orders.nk = {nk};
    ArxModel model = FitArx(y, u, orders, first);
    if (!best || model.loss < best->loss) best = std::move(model);
  }
  return *best;
}

TEST(FitArxOverDelays, EqualsOneFitPerCandidateAndFindsTheDelay) {
  for (const double noise : {0.001, 0.05}) {
    Eigen::VectorXd y, u;
    MakeRecord(3000, 13, noise, y, u);
    const ArxModel fast = FitArxOverDelays(y, u, 2, 2, 1, 40);
    const ArxModel reference = EveryCandidateFitted(y, u, 2, 2, 1, 40);
    EXPECT_EQ(fast.orders.nk, reference.orders.nk) << noise;
    EXPECT_EQ(fast.first_sample, reference.first_sample);
    EXPECT_NEAR(fast.loss, reference.loss, 1e-12 * reference.loss) << noise;
    ASSERT_EQ(fast.parameters.size(), reference.parameters.size());
    for (Eigen::Index i = 0; i < fast.parameters.size(); ++i) {
      EXPECT_NEAR(fast.parameters(i), reference.parameters(i), 1e-12) << noise << " " << i;
    }
    EXPECT_EQ(fast.orders.nk[0], 13) << noise;
  }
}

TEST(FitArxOverDelays, BadRangesAndSizesThrow) {
  Eigen::VectorXd y, u;
  MakeRecord(200, 3, 0.01, y, u);
  EXPECT_THROW(FitArxOverDelays(y, u, 2, 2, 0, 5), std::invalid_argument);
  EXPECT_THROW(FitArxOverDelays(y, u, 2, 2, 6, 5), std::invalid_argument);
  EXPECT_THROW(FitArxOverDelays(y.head(100), u, 2, 2, 1, 5), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
