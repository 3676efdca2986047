// The online model registry (core/online/online_model.h): each kind recovers a plant written in
// this file in closed form (ARX and LPV difference equations, the GL1 fractional recursion, an
// integrator with delay), from signals offset by an operating point it has to remove; names and
// units; flags; reset; the one rounding of seconds to samples; errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/online/online_model.h"
#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

OnlineModelSnapshot Snap(const OnlineModel& model) {
  OnlineModelSnapshot s;
  model.FillSnapshot(s);
  return s;
}

std::vector<std::string> Names(const OnlineModelSnapshot& s) {
  return {s.names.begin(), s.names.end()};
}

TEST(OnlineModelKinds, NamesRoundTripAndUnknownNamesAreRefused) {
  for (const OnlineModelKind kind : kOnlineModelKinds) {
    EXPECT_EQ(OnlineModelKindFromName(OnlineModelKindName(kind)), kind);
  }
  EXPECT_EQ(OnlineModelKindName(OnlineModelKind::kFractionalFoptd), "frac-foptd");
  EXPECT_FALSE(OnlineModelKindFromName("frac_foptd").has_value());
  EXPECT_FALSE(OnlineModelKindFromName("").has_value());
}

// Seconds become samples in one place, rounded to the nearest; out-of-range settings name
// themselves.
TEST(OnlineModelOptionsFor, RoundsSecondsToSamplesOnceAndNamesBadSettings) {
  OnlineModelSettings s;
  s.sample_time_s = 60.0;
  s.min_delay_s = 89.0;          // 1.48 samples -> 1
  s.max_delay_s = 1364.0;        // 22.7 -> 23
  s.fractional_delay_s = 150.0;  // 2.5 -> 3 (half away from zero)
  s.lpv_delay_s = 29.0;          // 0.48 -> 0
  EXPECT_EQ(OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, s).id.min_delay_samples, 1);
  EXPECT_EQ(OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, s).id.max_delay_samples, 23);
  EXPECT_EQ(OnlineModelOptionsFor(OnlineModelKind::kArx, s).arx.max_delay_samples, 23);
  EXPECT_EQ(OnlineModelOptionsFor(OnlineModelKind::kFractionalFoptd, s).fractional.delay_samples,
            3);
  EXPECT_EQ(OnlineModelOptionsFor(OnlineModelKind::kLpvArx, s).lpv.delay_samples, 0);

  // Constant trace needs a finite trace bound: the initial trace n p0.
  s.rls_method = RlsMethod::kConstantTrace;
  EXPECT_DOUBLE_EQ(OnlineModelOptionsFor(OnlineModelKind::kArx, s).arx.rls.trace_max, 4 * 1e10);
  s.initial_covariance = 50.0;
  EXPECT_DOUBLE_EQ(OnlineModelOptionsFor(OnlineModelKind::kArx, s).arx.rls.trace_max, 4 * 50.0);
  s.initial_covariance.reset();

  auto message = [](OnlineModelKind kind, const OnlineModelSettings& bad) -> std::string {
    try {
      OnlineModelOptionsFor(kind, bad);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  };
  OnlineModelSettings bad = s;
  bad.fractional_delay_s = kNan;
  EXPECT_NE(message(OnlineModelKind::kFractionalFoptd, bad).find("fractional_delay_s"),
            std::string::npos);
  bad = s;
  bad.lpv_delay_s = 1e300;  // would overflow int samples
  EXPECT_NE(message(OnlineModelKind::kLpvArx, bad).find("lpv_delay_s"), std::string::npos);
  bad = s;
  bad.sample_time_s = 0.0;
  EXPECT_NE(message(OnlineModelKind::kArx, bad).find("sample_time_s"), std::string::npos);
  bad = s;
  bad.arx_nb = 0;
  EXPECT_NE(message(OnlineModelKind::kArx, bad).find("nb"), std::string::npos);
  bad = s;
  bad.fractional_alphas = {0.5, 2.5};
  EXPECT_NE(message(OnlineModelKind::kFractionalFoptd, bad).find("alphas"), std::string::npos);
}

OnlineModelSettings Settings(double ts) {
  OnlineModelSettings s;
  s.sample_time_s = ts;
  s.initial_covariance = 1e8;  // with lambda = 1: the batch least-squares estimate
  return s;
}

// y(k) = 0.9 y(k-1) + 0.5 u(k-3) in deviations from (u0, y0) = (1.2, 2.0): the bank over delays
// 1..6 picks 3 samples and finds a1 = -0.9, b1 = 0.5 (MATLAB's sign), the operating point the first
// sample's.
TEST(OnlineArxModel, RecoversAnArxPlantAroundItsOperatingPoint) {
  OnlineModelSettings settings = Settings(2.0);
  settings.arx_na = 1;
  settings.arx_nb = 1;
  settings.min_delay_s = 2.0;
  settings.max_delay_s = 12.0;
  auto model = MakeOnlineModel(OnlineModelOptionsFor(OnlineModelKind::kArx, settings));
  ASSERT_EQ(model->kind(), OnlineModelKind::kArx);
  // The record starts at rest: the first sample is the equilibrium.
  std::vector<double> u = testdata::Prbs(600, 3, 7);
  u[0] = 0.0;
  std::vector<double> y(u.size(), 0.0);
  for (std::size_t k = 3; k < u.size(); ++k) y[k] = 0.9 * y[k - 1] + 0.5 * u[k - 3];
  for (std::size_t k = 0; k < u.size(); ++k) {
    OnlineSample s;
    s.input = 1.2 + u[k];
    s.level_m = 2.0 + y[k];
    model->Update(s);
  }
  const OnlineModelSnapshot s = Snap(*model);
  ASSERT_TRUE(s.valid);
  EXPECT_EQ(Names(s), (std::vector<std::string>{"delay_s", "a1", "b1", "input_operating_point",
                                                "level_operating_point_m"}));
  EXPECT_EQ(s.Value("delay_s"), 6.0);
  EXPECT_NEAR(s.Value("a1"), -0.9, 1e-6);
  EXPECT_NEAR(s.Value("b1"), 0.5, 1e-6);
  EXPECT_EQ(s.Value("input_operating_point"), 1.2);
  EXPECT_EQ(s.Value("level_operating_point_m"), 2.0);
  EXPECT_EQ(s.flags, 0);
  EXPECT_EQ(s.estimator, "rls-bank");
  EXPECT_GT(s.samples_used, 500);

  // A delay at the top of the bank may lie outside it: flagged.
  settings.max_delay_s = 6.0;
  auto edge = MakeOnlineModel(OnlineModelOptionsFor(OnlineModelKind::kArx, settings));
  for (std::size_t k = 0; k < u.size(); ++k) {
    OnlineSample in;
    in.input = 1.2 + u[k];
    in.level_m = 2.0 + y[k];
    edge->Update(in);
  }
  EXPECT_EQ(Snap(*edge).Value("delay_s"), 6.0);
  EXPECT_NE(Snap(*edge).flags & kFlagOutOfBounds, 0);

  // Reset: no estimate, and a new operating point from the next sample.
  model->Reset();
  EXPECT_FALSE(Snap(*model).valid);
  OnlineSample next;
  next.input = 5.0;
  next.level_m = 7.0;
  model->Update(next);
  EXPECT_EQ(Snap(*model).Value("input_operating_point"), 5.0);
}

// GL binomial weights w_j of (1 - z^-1)^alpha, by their recurrence (independent of core).
std::vector<double> GlWeights(double alpha, int count) {
  std::vector<double> w(static_cast<std::size_t>(count) + 1);
  w[0] = 1.0;
  for (int j = 1; j <= count; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    w[uj] = w[uj - 1] * (1.0 - (alpha + 1.0) / j);
  }
  return w;
}

// K e^{-d h s} / (1 + T s^alpha) discretised with GL1 and memory L, exactly the recursion
// (1 + c) y(k) + c sum_{j=1..L} w_j y(k-j) = K u(k-d), c = T / h^alpha: the bank picks alpha from
// its grid and recovers K and T to the parabola's interpolation between grid points of tc
// (T = 10 s^0.7 puts tc = 26.9 s between the grid's 24.5 and 30.9 s: 0.07 % off).
TEST(OnlineFractionalModel, RecoversAGlFractionalPlantAndItsAlpha) {
  const double h = 0.15, alpha = 0.7, gain = 0.37, t_const = 10.0;
  const int delay = 27, memory = 200;
  OnlineModelSettings settings = Settings(h);
  settings.fractional_alphas = {0.5, 0.6, 0.7, 0.8, 0.9};
  settings.fractional_delay_s = delay * h;
  settings.fractional_memory_s = memory * h;
  auto model = MakeOnlineModel(OnlineModelOptionsFor(OnlineModelKind::kFractionalFoptd, settings));
  const double c = t_const / std::pow(h, alpha);
  const std::vector<double> w = GlWeights(alpha, memory);
  std::vector<double> u = testdata::Prbs(2400, 40, 3);
  u[0] = 0.0;  // at rest
  std::vector<double> y(u.size(), 0.0);
  for (std::size_t k = 0; k < u.size(); ++k) {
    double sum = 0.0;
    for (std::size_t j = 1; j <= static_cast<std::size_t>(memory) && j <= k; ++j) {
      sum += w[j] * y[k - j];
    }
    const double ud = k >= static_cast<std::size_t>(delay) ? u[k - delay] : 0.0;
    y[k] = (gain * ud - c * sum) / (1.0 + c);
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    OnlineSample s;
    s.input = 0.015 + 0.002 * u[k];
    s.level_m = 0.05 + 0.002 * y[k];
    model->Update(s);
  }
  const OnlineModelSnapshot s = Snap(*model);
  ASSERT_TRUE(s.valid);
  EXPECT_EQ(Names(s),
            (std::vector<std::string>{"gain", "time_constant_s", "alpha", "delay_s",
                                      "input_operating_point", "level_operating_point_m"}));
  EXPECT_EQ(s.Value("alpha"), 0.7);
  EXPECT_NEAR(s.Value("gain"), gain, 2e-3 * gain);
  EXPECT_NEAR(s.Value("time_constant_s"), t_const, 2e-3 * t_const);
  EXPECT_NEAR(s.Value("delay_s"), delay * h, 1e-12);
  // The level at rest: the first sample's, the fitted offset near 0 on a plant that starts there.
  EXPECT_NEAR(s.Value("level_operating_point_m"), 0.05, 1e-7);
  EXPECT_EQ(s.flags & (kFlagNan | kFlagIllConditioned | kFlagOutOfBounds), 0) << s.flags;
  EXPECT_GT(s.excitation, 0.0);
}

// The standard deviations of K and T (K's at its grid point plus what it moves with tc; T's from
// the loss's curvature in log tc): with white output noise, 95 % of 40 realisations put the
// truth within 2 sigma (a loose check that holds for a right sigma; a sigma 3 x too small fails
// it).
TEST(OnlineFractionalModel, GainAndTimeConstantSigmasCoverTheTruth) {
  const double h = 0.15, alpha = 0.8, gain = 0.5, t_const = 5.0;
  const int memory = 100;
  OnlineModelSettings settings = Settings(h);
  settings.fractional_alphas = {alpha};
  settings.fractional_memory_s = memory * h;
  const double c = t_const / std::pow(h, alpha);
  const std::vector<double> w = GlWeights(alpha, memory);
  int gain_covered = 0, t_covered = 0;
  const int runs = 40;
  for (int run = 0; run < runs; ++run) {
    auto model =
        MakeOnlineModel(OnlineModelOptionsFor(OnlineModelKind::kFractionalFoptd, settings));
    testdata::TestRandom rnd(100 + static_cast<std::uint64_t>(run));
    std::vector<double> u = testdata::Prbs(1500, 20, 50 + static_cast<std::uint64_t>(run));
    u[0] = 0.0;  // at rest
    std::vector<double> x(u.size(), 0.0);
    for (std::size_t k = 0; k < u.size(); ++k) {
      double sum = 0.0;
      for (std::size_t j = 1; j <= static_cast<std::size_t>(memory) && j <= k; ++j) {
        sum += w[j] * x[k - j];
      }
      x[k] = (gain * u[k] - c * sum) / (1.0 + c);
    }
    for (std::size_t k = 0; k < u.size(); ++k) {
      OnlineSample s;
      s.input = u[k];
      // Output error: white noise on the measured level (the model's least-squares assumption).
      s.level_m = x[k] + (k == 0 ? 0.0 : 0.02 * rnd.Normal());
      model->Update(s);
    }
    const OnlineModelSnapshot s = Snap(*model);
    ASSERT_TRUE(s.valid);
    gain_covered += std::abs(s.Value("gain") - gain) < 2.0 * s.std_devs[0];
    t_covered += std::abs(s.Value("time_constant_s") - t_const) < 2.0 * s.std_devs[1];
  }
  EXPECT_GE(gain_covered, 33) << "of " << runs;
  EXPECT_GE(t_covered, 33) << "of " << runs;
}

// y(k) = -a1(s) y(k-1) + b1(s) u(k-2), a1(s) = -0.8 - 0.05 s, b1(s) = 0.3 + 0.1 s + 0.02 s^2, in
// deviations; the scheduling variable s is used raw.
TEST(OnlineLpvModel, RecoversQuadraticCoefficientsInTheSchedulingVariable) {
  OnlineModelSettings settings = Settings(60.0);
  settings.lpv_delay_s = 120.0;
  auto model = MakeOnlineModel(OnlineModelOptionsFor(OnlineModelKind::kLpvArx, settings));
  std::vector<double> u = testdata::Prbs(800, 2, 11);
  u[0] = 0.0;  // at rest
  testdata::TestRandom rnd(4);
  std::vector<double> y(u.size(), 0.0), sched(u.size(), 0.0);
  for (std::size_t k = 0; k < u.size(); ++k) sched[k] = 2.0 * rnd.Uniform();
  for (std::size_t k = 2; k < u.size(); ++k) {
    const double s = sched[k];
    const double a1 = -0.8 - 0.05 * s;
    const double b1 = 0.3 + 0.1 * s + 0.02 * s * s;
    y[k] = -a1 * y[k - 1] + b1 * u[k - 2];
  }
  for (std::size_t k = 0; k < u.size(); ++k) {
    OnlineSample in;
    in.input = 3.0 + u[k];
    in.level_m = 10.0 + y[k];
    in.scheduling = sched[k];
    model->Update(in);
  }
  const OnlineModelSnapshot s = Snap(*model);
  ASSERT_TRUE(s.valid);
  EXPECT_EQ(Names(s),
            (std::vector<std::string>{"delay_s", "a1_0", "a1_1", "a1_2", "b1_0", "b1_1", "b1_2",
                                      "input_operating_point", "level_operating_point_m"}));
  EXPECT_EQ(s.Value("delay_s"), 120.0);
  EXPECT_NEAR(s.Value("a1_0"), -0.8, 1e-6);
  EXPECT_NEAR(s.Value("a1_1"), -0.05, 1e-6);
  EXPECT_NEAR(s.Value("a1_2"), 0.0, 1e-6);
  EXPECT_NEAR(s.Value("b1_0"), 0.3, 1e-6);
  EXPECT_NEAR(s.Value("b1_1"), 0.1, 1e-6);
  EXPECT_NEAR(s.Value("b1_2"), 0.02, 1e-6);
  EXPECT_EQ(s.estimator, "rls");
}

// The id kind publishes the bank's selected model under the names the daemon always used.
TEST(OnlineIntegratorDelayModel, PublishesTheBanksModel) {
  OnlineModelSettings settings = Settings(60.0);
  settings.max_delay_s = 20 * 60.0;
  const OnlineModelOptions options =
      OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, settings);
  auto model = MakeOnlineModel(options);
  OnlineIntegratorDelayBank direct(options.id);
  testdata::PoolSpec spec;
  spec.samples = 1500;
  const testdata::PoolData d = testdata::MakePool(spec);
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    OnlineSample s;
    s.q_in_m3s = d.q_in[k];
    s.q_out_m3s = d.q_out[k];
    s.level_m = d.level[k];
    model->Update(s);
    direct.Update(d.q_in[k], d.q_out[k], d.level[k]);
  }
  const OnlineModelSnapshot s = Snap(*model);
  ASSERT_TRUE(s.valid);
  ASSERT_NE(model->integrator_delay_bank(), nullptr);
  EXPECT_EQ(Names(s), (std::vector<std::string>{"delay_s", "area_m2", "b", "offset_m",
                                                "drift_m_per_sample"}));
  // The plant of MakePool: nk = 7 samples, A = 6000 m^2.
  EXPECT_EQ(s.Value("delay_s"), 7 * 60.0);
  EXPECT_NEAR(s.Value("area_m2"), 6000.0, 0.05 * 6000.0);
  const IntegratorDelaySnapshot bank = direct.Snapshot();
  EXPECT_EQ(s.Value("area_m2"), bank.area_m2);
  EXPECT_EQ(s.std_devs[1], bank.area_std_m2);
  EXPECT_EQ(s.flags, bank.flags);
}

// Bad values: NaN inputs or levels are counted, never poison the estimate.
TEST(OnlineModel, InvalidSamplesLeaveEveryKindFinite) {
  OnlineModelSettings settings = Settings(1.0);
  settings.max_delay_s = 4.0;
  settings.fractional_delay_s = 1.0;
  settings.lpv_delay_s = 1.0;
  const std::vector<double> u = testdata::Prbs(400, 3, 2);
  for (const OnlineModelKind kind : kOnlineModelKinds) {
    auto model = MakeOnlineModel(OnlineModelOptionsFor(kind, settings));
    double y = 0.0;
    for (std::size_t k = 0; k < u.size(); ++k) {
      y = 0.8 * y + 0.2 * (k >= 1 ? u[k - 1] : 0.0);
      OnlineSample s;
      s.q_in_m3s = 1.0 + 0.1 * u[k];
      s.q_out_m3s = 1.0;
      s.input = k % 50 == 7 ? kNan : u[k];
      s.level_m = k % 40 == 9 ? kNan : y;
      s.scheduling = k % 60 == 11 ? kNan : 0.5;
      model->Update(s);
    }
    const OnlineModelSnapshot s = Snap(*model);
    ASSERT_TRUE(s.valid) << OnlineModelKindName(kind);
    for (int i = 0; i < s.num_params; ++i) {
      EXPECT_TRUE(std::isfinite(s.values[static_cast<std::size_t>(i)]))
          << OnlineModelKindName(kind) << " " << s.names[static_cast<std::size_t>(i)];
    }
    EXPECT_EQ(s.flags & kFlagNan, 0) << OnlineModelKindName(kind);
  }
}

}  // namespace
}  // namespace canalid::core
