// ArxCandidates against one Rls<Dynamic> per candidate fed the same rows (the estimators the
// online ARX bank ran before): every candidate's estimate, loss, rejections and the delay the
// selector picks, for orders run as RlsBank lanes and above them.
#include "core/online/arx_candidates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace canalid::core {
namespace {

struct Orders {
  int na;
  int nb;
  // kUdDirectional runs the lanes as structure of arrays; the covariance forms lane by lane.
  RlsMethod method = RlsMethod::kUdDirectional;
  BankCriterion criterion = BankCriterion::kResidual;
};

class ArxCandidatesAgainstRls : public ::testing::TestWithParam<Orders> {};

TEST_P(ArxCandidatesAgainstRls, EveryCandidateMatchesItsOwnEstimator) {
  const auto [na, nb, method, criterion] = GetParam();
  const int n = na + nb;
  constexpr int kMinDelay = 2;
  constexpr int kCount = 6;  // delays 2..7: one full block of lanes and a part-filled one
  RlsOptions options;
  options.forgetting = 0.995;
  options.method = method;
  const auto candidates = ArxCandidates::Make(options, n, kCount);
  EXPECT_EQ(candidates->lanes(),
            n <= ArxCandidates::kMaxArxLaneParams && method == RlsMethod::kUdDirectional);
  std::vector<Rls<Eigen::Dynamic>> reference(kCount, Rls<Eigen::Dynamic>(options, n));
  const BankSelectorOptions choice{.criterion = criterion};
  BankSelector selector(kCount, choice);
  BankSelector reference_selector(kCount, choice);

  RingBuffer<double> u(kMinDelay + kCount + nb);
  RingBuffer<std::uint8_t> u_bad(kMinDelay + kCount + nb);
  RingBuffer<double> y(na + 1);
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  double level = 0.0;
  int rejected_rows = 0;
  for (int k = 0; k < 600; ++k) {
    const bool bad = k % 53 == 30;  // a dropout: the rows that read it are rejected
    u.Push(bad ? 0.0 : std::sin(0.37 * k) + (k % 17 < 8 ? 1.0 : -1.0));
    u_bad.Push(bad ? 1 : 0);
    if (k >= kMinDelay + kCount + nb) {
      std::vector<double> minus_y(static_cast<std::size_t>(na));
      for (int i = 0; i < na; ++i) minus_y[static_cast<std::size_t>(i)] = -y[i];
      const double out = 0.8 * level + 0.3 * u[4] + noise(random);  // delay 4
      const ArxRows rows{.na = na,
                         .nb = nb,
                         .min_delay = kMinDelay,
                         .minus_y_lags = minus_y.data(),
                         .u = &u,
                         .u_bad = &u_bad};
      candidates->Update(rows, out, selector);
      for (int c = 0; c < kCount; ++c) {
        Eigen::VectorXd phi(n);
        bool good = true;
        for (int i = 0; i < na; ++i) phi(i) = -y[i];
        for (int j = 0; j < nb; ++j) {
          phi(na + j) = u[kMinDelay + c + j];
          good = good && u_bad[kMinDelay + c + j] == 0;
        }
        if (!good) {
          ++rejected_rows;
          continue;  // the estimator before: the row never reached it
        }
        auto& rls = reference[static_cast<std::size_t>(c)];
        const auto result = rls.Update(phi, out);
        if (criterion == BankCriterion::kResidual) {
          reference_selector.SetLoss(c, rls.residual_sum_of_squares());
        } else {
          reference_selector.Record(c, result.prediction_error);
        }
      }
      selector.Commit();
      reference_selector.Commit();
      ASSERT_EQ(selector.selected(), reference_selector.selected()) << k;
      level = out;
    }
    y.Push(level);
  }
  ASSERT_GT(rejected_rows, 0);
  int rejected = 0;
  for (int c = 0; c < kCount; ++c) {
    ArxCandidateState state;
    candidates->State(c, state);
    const auto& rls = reference[static_cast<std::size_t>(c)];
    ASSERT_EQ(state.theta.size(), n);
    // Rls<n> (the lanes) and Rls<Dynamic> may round differently (Eigen's fixed and dynamic
    // kernels): equal to the last few bits, not necessarily to the bit.  The covariance forms
    // carry that rounding in P from sample to sample: with kKalman 7e-11 was measured after 600
    // samples, so they are held to 1e-9 (the UD forms to 1e-12).
    const double tolerance = method == RlsMethod::kUdDirectional ? 1e-12 : 1e-9;
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(state.theta(i), rls.theta()(i), tolerance * (1.0 + std::abs(rls.theta()(i))))
          << c << " " << i;
      EXPECT_NEAR(state.std_dev(i), rls.StandardDeviation(i), 1e-9 * rls.StandardDeviation(i))
          << c << " " << i;
    }
    EXPECT_NEAR(state.innovation_variance, rls.innovation_variance(),
                tolerance * rls.innovation_variance());
    EXPECT_EQ(state.health.updates, rls.health().updates) << c;
    rejected += static_cast<int>(state.health.rejected_invalid);
  }
  // Each row reading the dropout is rejected by its candidate, and only those.
  EXPECT_EQ(rejected, rejected_rows);
}

INSTANTIATE_TEST_SUITE_P(
    Orders, ArxCandidatesAgainstRls,
    ::testing::Values(Orders{0, 1}, Orders{2, 2}, Orders{4, 4}, Orders{4, 5},
                      Orders{2, 2, RlsMethod::kExponential, BankCriterion::kPredictionError},
                      Orders{3, 2, RlsMethod::kKalman, BankCriterion::kPredictionError}),
    [](const ::testing::TestParamInfo<Orders>& p) {
      return "na" + std::to_string(p.param.na) + "nb" + std::to_string(p.param.nb) + "_" +
             std::to_string(p.index);
    });

}  // namespace
}  // namespace canalid::core
