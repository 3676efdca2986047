// `--model idz` (FitIdz through IdentifyIdz) on records of an IDZ plant written from the IDZ
// equations (sim::IdzPlant, continuous time, a delay that is not a whole number of samples), with
// 3 mm of level noise, in the three situations users have: the outflow held, the outflow moved on
// its own (a second structure), and a gate whose outflow follows the level (closed loop).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/integrator_delay/identify_idz.h"
#include "core/numerics/splitmix64.h"
#include "core/signal/prbs.h"
#include "sim/pool_plant.h"

namespace canalid::sim {
namespace {

// ASCE canal 2 pool 2 at 10 m3/s (Litrico & Fromion 2004).
constexpr double kDelay = 682.0, kArea = 34113.0, kP21 = 0.0185, kP22 = 0.0216;
constexpr double kLevel0 = 2.1, kFlow0 = 10.0, kTs = 60.0;
constexpr int kSamples = 840;

enum class Outflow { kHeld, kOwnPrbs, kLevelDrivenGate };

struct Record {
  Eigen::VectorXd q_in, q_out, level;
};

Record Simulate(Outflow outflow) {
  IdzPlant plant(kDelay, kArea, kP21, kP22, kLevel0, kFlow0);
  core::PrbsSignalSpec in;
  in.nominal = kFlow0;
  in.amplitude = 0.8;
  in.clock_period_samples = 6;  // half the delay
  in.order = 7;
  const Eigen::VectorXd inflow = core::GeneratePrbs(in, kSamples);
  core::PrbsSignalSpec out = in;
  out.amplitude = 0.5;
  out.clock_period_samples = 5;
  out.seed = 77;
  const Eigen::VectorXd own = core::GeneratePrbs(out, kSamples);
  constexpr double kGateGain = 14.6;  // m2/s: dq_out/dy of the fixed gate at the end of pool 2
  core::SplitMix64 rng(2024);
  Record r{Eigen::VectorXd(kSamples), Eigen::VectorXd(kSamples), Eigen::VectorXd(kSamples)};
  double q_out = kFlow0;
  for (int k = 0; k < kSamples; ++k) {
    // Outflow over this sample: held, its own PRBS, or the gate following the level (updated
    // every 5 s so the loop acts continuously).
    for (int sub = 0; sub < 12; ++sub) {
      if (outflow == Outflow::kLevelDrivenGate) {
        q_out = kFlow0 + kGateGain * (plant.level_m() - kLevel0);
      } else {
        q_out = outflow == Outflow::kOwnPrbs ? own(k) : kFlow0;
      }
      plant.SetFlows(inflow(k), q_out);
      if (sub == 0) {
        // All three read at the same instant, the flows just set (the level's direct terms see
        // them at once, as a sensor would).
        r.q_in(k) = inflow(k);
        r.q_out(k) = q_out;
        // Box-Muller: 3 mm of Gaussian noise on the level sensor.
        const double u1 = 1.0 - rng.NextUniform(), u2 = rng.NextUniform();
        r.level(k) =
            plant.level_m() + 0.003 * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
      }
      plant.Step(kTs / 12.0);
    }
  }
  return r;
}

core::IdzFit Fit(const Record& r, double prior = -1.0) {
  core::IdzIdentificationOptions options;
  options.fit.max_nk = 30;
  options.fit.p22_prior_s_per_m2 = prior;
  options.fit.p22_prior_std_s_per_m2 = prior > 0.0 ? 0.2 * prior : 0.0;
  return core::IdentifyIdz(r.q_in, r.q_out, r.level, kTs, options).fit;
}

void ExpectDelayAndArea(const core::IdzFit& fit) {
  std::cout << "delay " << fit.delay_s() << " s, area " << fit.area_m2 << " +- " << fit.area_std_m2
            << " m2, p21 " << fit.p21_s_per_m2 << ", p22 " << fit.p22_s_per_m2 << " +- "
            << fit.p22_std_s_per_m2 << " (" << core::OutflowGainSourceName(fit.p22_source) << ")\n";
  // The delay in whole samples: 682 s lies between 660 and 720.
  EXPECT_NEAR(fit.delay_s() / kDelay, 1.0, 0.06) << "delay " << fit.delay_s();
  // The issue asks 10 %; on the model's own structure it does much better (measured <= 0.7 %).
  EXPECT_NEAR(fit.area_m2 / kArea, 1.0, 0.03) << "area " << fit.area_m2;
}

// The fit's delay is whole samples (720 s for the plant's 682 s): the ramp then starts 38 s late,
// and the front makes up the volume, 38 s x dq / A, so the zero-order-hold equation's p21 is the
// plant's plus (delay - 682 s) / A (0.0185 + 0.0011; measured within 0.1 % of it).
double P21WithTheDelaysRounding(const core::IdzFit& fit) {
  return kP21 + (fit.delay_s() - kDelay) / kArea;
}

TEST(IdzFitPlant, HeldOutflowGivesTheAreaAndNoP22) {
  const core::IdzFit fit = Fit(Simulate(Outflow::kHeld));
  ExpectDelayAndArea(fit);
  EXPECT_NEAR(fit.p21_s_per_m2 / P21WithTheDelaysRounding(fit), 1.0, 0.01) << fit.p21_s_per_m2;
  EXPECT_EQ(fit.p22_source, core::OutflowGainSource::kNone);
  EXPECT_FALSE(fit.outflow_moves);
  EXPECT_TRUE(fit.warnings.empty());
}

TEST(IdzFitPlant, OutflowMovedOnItsOwnGivesP22FromTheData) {
  const core::IdzFit fit = Fit(Simulate(Outflow::kOwnPrbs), 0.01);
  ExpectDelayAndArea(fit);
  EXPECT_EQ(fit.p22_source, core::OutflowGainSource::kData) << fit.p22_reason;
  EXPECT_NEAR(fit.p22_s_per_m2 / kP22, 1.0, 0.05) << fit.p22_s_per_m2;
  EXPECT_NEAR(fit.p21_s_per_m2 / P21WithTheDelaysRounding(fit), 1.0, 0.01) << fit.p21_s_per_m2;
  EXPECT_GT(fit.p22_std_s_per_m2, 0.0);
  EXPECT_LT(fit.p22_std_s_per_m2, 0.05 * kP22);
}

TEST(IdzFitPlant, LevelDrivenGateNeedsThePriorAndGetsTheAreaWithIt) {
  const Record record = Simulate(Outflow::kLevelDrivenGate);
  const core::IdzFit without = Fit(record);
  EXPECT_TRUE(without.outflow_follows_level);
  EXPECT_EQ(without.p22_source, core::OutflowGainSource::kNone);
  ASSERT_EQ(without.warnings.size(), 1u);
  // The area the ID regression reads in closed loop, A (1 + p22 g) = 1.32 A.
  std::cout << "without a prior: area " << without.area_m2 << " m2\n";
  EXPECT_GT(without.area_m2 / kArea, 1.2) << without.area_m2;
  const core::IdzFit with = Fit(record, kP22);
  EXPECT_EQ(with.p22_source, core::OutflowGainSource::kPrior) << with.p22_reason;
  ExpectDelayAndArea(with);
  EXPECT_DOUBLE_EQ(with.p22_s_per_m2, kP22);
  // The prior's 20 % uncertainty is carried into the area's.
  const core::IdzFit exact_prior = [&] {
    core::IdzIdentificationOptions options;
    options.fit.max_nk = 30;
    options.fit.p22_prior_s_per_m2 = kP22;
    return core::IdentifyIdz(record.q_in, record.q_out, record.level, kTs, options).fit;
  }();
  EXPECT_GT(with.area_std_m2, 2.0 * exact_prior.area_std_m2);
  EXPECT_DOUBLE_EQ(with.area_m2, exact_prior.area_m2);
}

TEST(IdzFitPlant, BadOptionsAreNamed) {
  const Record record = Simulate(Outflow::kHeld);
  core::IdzIdentificationOptions options;
  options.fit.p22_prior_s_per_m2 = 0.01;
  options.fit.p22_prior_std_s_per_m2 = -1.0;
  EXPECT_THROW(core::IdentifyIdz(record.q_in, record.q_out, record.level, kTs, options),
               std::invalid_argument);
  options.fit.p22_prior_std_s_per_m2 = 0.0;
  options.fit.min_nk = 40;
  options.fit.max_nk = 30;
  try {
    core::IdentifyIdz(record.q_in, record.q_out, record.level, kTs, options);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("IDZ fit: need 0 <= min_nk <= max_nk"), std::string::npos);
  }
}

}  // namespace
}  // namespace canalid::sim
