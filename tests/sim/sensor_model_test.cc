#include "sim/sensor_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace canalid::sim {
namespace {

TEST(SensorModel, PerfectSensorPassesValuesThrough) {
  SensorModel s(SensorConfig{}, 7);
  for (int k = 0; k < 100; ++k) EXPECT_EQ(s.Read(2.0 + k * 1e-3, k * 60.0, 60.0), 2.0 + k * 1e-3);
}

TEST(SensorModel, NoiseDriftQuantisationStatistics) {
  SensorConfig c;
  c.noise_std = 0.003;
  c.drift_per_h = 0.01;
  SensorModel s(c, 42);
  double sum = 0, sum2 = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double t = k * 60.0;
    const double e = s.Read(2.0, t, 60.0) - 2.0 - 0.01 * t / 3600.0;
    sum += e;
    sum2 += e * e;
  }
  // 20000 samples: the standard error of the mean is 2e-5 and of the std about 0.5 %.
  EXPECT_NEAR(sum / n, 0.0, 1e-4);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.003, 0.0001);
  SensorConfig q;
  q.quantum = 0.01;
  SensorModel quant(q, 1);
  EXPECT_DOUBLE_EQ(quant.Read(2.1234, 0, 1), 2.12);
}

TEST(SensorModel, SpikesStuckAndDropoutsAtTheirRates) {
  SensorConfig c;
  c.spike_rate_per_h = 1.0;
  c.spike_min = 0.15;
  c.spike_max = 0.4;
  SensorModel s(c, 3);
  int spikes = 0;
  const int n = 60 * 1000;  // 1000 h of 60 s samples
  for (int k = 0; k < n; ++k) {
    const double e = std::abs(s.Read(2.0, k * 60.0, 60.0) - 2.0);
    if (e > 0) {
      ++spikes;
      EXPECT_GE(e, 0.15 - 1e-12);
      EXPECT_LE(e, 0.4 + 1e-12);
    }
  }
  // Poisson with mean 1000: +-10 % is over 3 standard deviations.
  EXPECT_NEAR(spikes, 1000, 100);

  SensorConfig d;
  d.dropout_rate_per_h = 1.0;
  d.dropout_duration_s = 600.0;
  SensorModel drop(d, 5);
  int missing = 0;
  for (int k = 0; k < n; ++k) missing += std::isnan(drop.Read(1.0, k * 60.0, 60.0)) ? 1 : 0;
  // About 1000 episodes of 10 samples, minus overlaps: between 6000 and 11000 samples.
  EXPECT_GT(missing, 6000);
  EXPECT_LT(missing, 11000);

  SensorConfig st;
  st.stuck_rate_per_h = 0.5;
  st.stuck_duration_s = 1800.0;
  SensorModel stuck(st, 9);
  int held = 0;
  double last = -1;
  for (int k = 0; k < n; ++k) {
    const double v = stuck.Read(k * 1.0, k * 60.0, 60.0);  // a ramp: equal readings mean stuck
    held += v == last ? 1 : 0;
    last = v;
  }
  EXPECT_GT(held, 5000);
  EXPECT_LT(held, 20000);
}

TEST(SensorModel, SameSeedSameReadings) {
  SensorConfig c;
  c.noise_std = 1.0;
  SensorModel a(c, 11), b(c, 11), other(c, 12);
  double diff = 0;
  for (int k = 0; k < 10; ++k) {
    const double va = a.Read(0, k, 1);
    EXPECT_EQ(va, b.Read(0, k, 1));
    diff += std::abs(va - other.Read(0, k, 1));
  }
  EXPECT_GT(diff, 0.0);
}

}  // namespace
}  // namespace canalid::sim
