#include "core/signal/outliers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "core/signal/prbs.h"

namespace canalid::core {
namespace {

// A pool level at 60 s sampling: integrator response to a PRBS inflow (0.5 mm per sample up or
// down, clock 20 samples), 3 mm Gaussian sensor noise.
Eigen::VectorXd CleanLevel(Eigen::Index n, unsigned seed, Eigen::VectorXd* noise_free) {
  PrbsSignalSpec spec;
  spec.nominal = 2.0;
  spec.amplitude = 0.0005;
  spec.clock_period_samples = 20;
  spec.order = 9;
  spec.integrate = true;
  *noise_free = GeneratePrbs(spec, n);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.003);
  Eigen::VectorXd y = *noise_free;
  for (Eigen::Index i = 0; i < n; ++i) y(i) += noise(rng);
  return y;
}

TEST(Outliers, FindsEveryIsolatedSpikeAndAlmostNothingElse) {
  const Eigen::Index n = 20000;
  Eigen::VectorXd truth;
  Eigen::VectorXd y = CleanLevel(n, 42, &truth);
  // 60 spikes of 0.15..0.4 m with random sign, at least 50 samples apart.
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> size(0.15, 0.4);
  std::set<Eigen::Index> spikes;
  for (Eigen::Index k = 0; k < 60; ++k) {
    const Eigen::Index at = 100 + k * 330 + static_cast<Eigen::Index>(rng() % 200);
    spikes.insert(at);
    y(at) += (rng() % 2 == 0 ? 1.0 : -1.0) * size(rng);
  }
  const OutlierResult r = RemoveOutliers(y);  // defaults: 31-sample window, 5 sigma
  EXPECT_EQ(r.report.count, static_cast<Eigen::Index>(r.report.replaced.size()));
  std::set<Eigen::Index> found(r.report.replaced.begin(), r.report.replaced.end());
  for (Eigen::Index at : spikes) EXPECT_TRUE(found.count(at)) << "missed spike at " << at;
  Eigen::Index false_positives = 0;
  for (Eigen::Index at : found) false_positives += spikes.count(at) ? 0 : 1;
  // At 5 sigma a Gaussian sample is flagged with probability ~6e-7; MAD-estimation noise in a
  // 31-sample window raises that, but far less than 1 in 2000.
  EXPECT_LE(false_positives, n / 2000) << "false positives: " << false_positives;
  // Replaced spikes are back within noise (4 sigma = 12 mm) plus interpolation error of the
  // slow signal (< 1 mm) of the true level.
  for (Eigen::Index at : spikes) EXPECT_NEAR(r.cleaned(at), truth(at), 0.013) << "at " << at;
  // Samples that were not replaced are untouched.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!found.count(i)) {
      ASSERT_EQ(r.cleaned(i), y(i));
    }
  }
}

TEST(Outliers, FalsePositiveRateOnCleanDataIsTiny) {
  const Eigen::Index n = 50000;
  Eigen::VectorXd truth;
  const Eigen::VectorXd y = CleanLevel(n, 7, &truth);
  const OutlierResult r = RemoveOutliers(y);
  EXPECT_LE(r.report.count, n / 10000) << r.report.count << " flagged of " << n;
}

TEST(Outliers, InterpolatesBetweenGoodNeighboursAndHoldsAtTheEnds) {
  // A ramp with a 2-sample burst inside and spikes on the first and last samples.
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(41, 0.0, 4.0);  // 0.1 per sample
  Eigen::VectorXd noisy = x;
  noisy(20) += 5.0;
  noisy(21) -= 7.0;
  noisy(0) = 9.0;
  noisy(40) = -9.0;
  HampelOptions options;
  options.half_window = 5;
  options.threshold_sigma = 3.0;
  const OutlierResult r = RemoveOutliers(noisy, options);
  EXPECT_EQ(r.report.replaced, (std::vector<Eigen::Index>{0, 20, 21, 40}));
  EXPECT_NEAR(r.cleaned(20), 2.0, 1e-12);  // interpolated between 1.9 and 2.2
  EXPECT_NEAR(r.cleaned(21), 2.1, 1e-12);
  EXPECT_DOUBLE_EQ(r.cleaned(0), 0.1);   // holds the first good sample
  EXPECT_DOUBLE_EQ(r.cleaned(40), 3.9);  // holds the last good sample
}

TEST(Outliers, MinSigmaProtectsFlatQuantisedStretches) {
  Eigen::VectorXd x = Eigen::VectorXd::Constant(100, 1.000);
  x(50) = 1.001;                                 // one quantum of 1 mm
  EXPECT_EQ(RemoveOutliers(x).report.count, 1);  // MAD = 0: any change is "infinitely" far
  HampelOptions options;
  options.min_sigma = 0.001;
  EXPECT_EQ(RemoveOutliers(x, options).report.count, 0);
}

TEST(Outliers, RejectsBadArguments) {
  HampelOptions options;
  options.half_window = 0;
  EXPECT_THROW(RemoveOutliers(Eigen::VectorXd::Zero(10), options), std::invalid_argument);
  options = {};
  options.threshold_sigma = 0.0;
  EXPECT_THROW(RemoveOutliers(Eigen::VectorXd::Zero(10), options), std::invalid_argument);
  options = {};
  options.min_sigma = -1.0;
  EXPECT_THROW(RemoveOutliers(Eigen::VectorXd::Zero(10), options), std::invalid_argument);
  EXPECT_THROW(RemoveOutliers(Eigen::VectorXd()), std::invalid_argument);
  Eigen::VectorXd bad = Eigen::VectorXd::Zero(10);
  bad(3) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(RemoveOutliers(bad), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
