#include "core/signal/prbs.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace canalid::core {
namespace {

// --- An independent truth for the tap table: a polynomial p over GF(2) of degree n with p(0) = 1
// is primitive iff x has multiplicative order exactly 2^n - 1 modulo p.  This checks the table
// algebraically for every order, including 21..31 whose periods are too long to walk.

std::uint64_t MulMod(std::uint64_t a, std::uint64_t b, std::uint64_t p, int n) {
  std::uint64_t product = 0;
  for (int i = 0; i < n; ++i) {
    if ((b >> i) & 1U) product ^= a << i;
  }
  for (int bit = 2 * n - 2; bit >= n; --bit) {
    if ((product >> bit) & 1U) product ^= p << (bit - n);
  }
  return product;
}

std::uint64_t PowXMod(std::uint64_t e, std::uint64_t p, int n) {
  std::uint64_t result = 1;
  std::uint64_t base = 2;  // the polynomial x
  while (e > 0) {
    if (e & 1U) result = MulMod(result, base, p, n);
    base = MulMod(base, base, p, n);
    e >>= 1;
  }
  return result;
}

std::vector<std::uint64_t> PrimeFactors(std::uint64_t m) {
  std::vector<std::uint64_t> factors;
  for (std::uint64_t q = 2; q * q <= m; ++q) {
    if (m % q == 0) {
      factors.push_back(q);
      while (m % q == 0) m /= q;
    }
  }
  if (m > 1) factors.push_back(m);
  return factors;
}

TEST(Prbs, EveryTapSetIsAPrimitivePolynomial) {
  for (int n = kMinLfsrOrder; n <= kMaxLfsrOrder; ++n) {
    // Characteristic polynomial of a(t) = sum_k a(t-k): x^n + sum_k x^(n-k).
    std::uint64_t p = std::uint64_t{1} << n;
    for (int k : LfsrTaps(n)) p ^= std::uint64_t{1} << (n - k);
    ASSERT_EQ(p & 1U, 1U) << "order " << n << " must contain tap n";
    const std::uint64_t group = (std::uint64_t{1} << n) - 1;
    EXPECT_EQ(PowXMod(group, p, n), 1U) << "order " << n;
    for (std::uint64_t q : PrimeFactors(group)) {
      EXPECT_NE(PowXMod(group / q, p, n), 1U) << "order " << n << " factor " << q;
    }
  }
}

TEST(Prbs, StateCycleIsMaximalAndBalancedForOrders2To20) {
  // Walk the whole state cycle: the start state must come back after exactly 2^n - 1 clocks and
  // not before, and each period has 2^(n-1) ones and 2^(n-1) - 1 minus ones.
  for (int n = 2; n <= 20; ++n) {
    MaximalLengthSequence s(n, 1);
    const std::int64_t period = (std::int64_t{1} << n) - 1;
    ASSERT_EQ(s.period(), period);
    std::int64_t plus = 0;
    std::int64_t steps = 0;
    do {
      plus += s.Next() > 0 ? 1 : 0;
      ++steps;
    } while (s.state() != 1U && steps <= period);
    EXPECT_EQ(steps, period) << "order " << n;
    EXPECT_EQ(plus, std::int64_t{1} << (n - 1)) << "order " << n;
    EXPECT_EQ(period - plus, (std::int64_t{1} << (n - 1)) - 1) << "order " << n;
  }
}

TEST(Prbs, AutocorrelationIsTwoValued) {
  for (int n : {2, 3, 5, 8, 10, 12}) {
    MaximalLengthSequence s(n, n == 2 ? 1U : 5U);
    const int period = static_cast<int>(s.period());
    std::vector<int> x(static_cast<std::size_t>(period));
    for (int& v : x) v = s.Next();
    for (int lag = 0; lag < period; ++lag) {
      int sum = 0;
      for (int t = 0; t < period; ++t) {
        sum += x[static_cast<std::size_t>(t)] * x[static_cast<std::size_t>((t + lag) % period)];
      }
      ASSERT_EQ(sum, lag == 0 ? period : -1) << "order " << n << " lag " << lag;
    }
  }
}

TEST(Prbs, Order31PrefixFollowsItsRecurrenceAndLooksWhite) {
  MaximalLengthSequence s(31, 0x5A5A5A5AU);
  const int m = 1 << 20;
  std::vector<int> x(static_cast<std::size_t>(m));
  for (int& v : x) v = s.Next();
  // Recurrence with taps 31, 28 holds on the bits (+1 -> 1, -1 -> 0).
  for (int t = 31; t < m; ++t) {
    const int bit = (x[static_cast<std::size_t>(t)] > 0) ? 1 : 0;
    const int b31 = (x[static_cast<std::size_t>(t - 31)] > 0) ? 1 : 0;
    const int b28 = (x[static_cast<std::size_t>(t - 28)] > 0) ? 1 : 0;
    ASSERT_EQ(bit, b31 ^ b28) << "t " << t;
  }
  // On a prefix of M values a random-like +-1 sequence has |sum| and |autocorrelation| of order
  // sqrt(M) = 1024; 5 sqrt(M) would be exceeded with probability < 1e-6 by a white sequence.
  long long sum = 0;
  for (int v : x) sum += v;
  EXPECT_LT(std::llabs(sum), 5 * 1024);
  for (int lag : {1, 2, 3, 28, 31, 59, 1000}) {
    long long r = 0;
    for (int t = 0; t + lag < m; ++t) {
      r += static_cast<long long>(x[static_cast<std::size_t>(t)]) *
           x[static_cast<std::size_t>(t) + static_cast<std::size_t>(lag)];
    }
    EXPECT_LT(std::llabs(r), 5 * 1024) << "lag " << lag;
  }
}

TEST(Prbs, SignalHoldsEachBitForTheClockPeriod) {
  PrbsSignalSpec spec;
  spec.nominal = 2.0;
  spec.amplitude = 0.15;
  spec.clock_period_samples = 4;
  spec.order = 5;
  spec.seed = 3;
  const Eigen::VectorXd u = GeneratePrbs(spec, 248);  // two periods of 31 bits of 4 samples
  MaximalLengthSequence s(5, 3);
  for (int clock = 0; clock < 62; ++clock) {
    const double expected = 2.0 + 0.15 * s.Next();
    for (int j = 0; j < 4; ++j) EXPECT_DOUBLE_EQ(u(clock * 4 + j), expected);
  }
  // Two levels only, and the period repeats.
  EXPECT_EQ(u.head(124), u.tail(124));
  EXPECT_NEAR(u.head(124).mean(), 2.0 + 0.15 * 4.0 / 124.0, 1e-12);  // one extra +1 clock
  PrbsGenerator generator(spec);
  EXPECT_EQ(generator.period_samples(), 124);
}

TEST(Prbs, IntegratedSignalIsTheRunningSumOfThePlainOne) {
  PrbsSignalSpec plain;
  plain.nominal = 0.0;
  plain.amplitude = 1.0;
  plain.clock_period_samples = 3;
  plain.order = 4;
  PrbsSignalSpec integrated = plain;
  integrated.nominal = 10.0;
  integrated.amplitude = 0.01;
  integrated.integrate = true;
  const Eigen::VectorXd s = GeneratePrbs(plain, 90);
  const Eigen::VectorXd u = GeneratePrbs(integrated, 90);
  double sum = 0.0;
  for (int k = 0; k < 90; ++k) {
    sum += s(k);
    EXPECT_NEAR(u(k), 10.0 + 0.01 * sum, 1e-12);
  }
  // After one full period (15 clocks x 3 samples) the drift is one clock of +1.
  EXPECT_NEAR(u(44), 10.0 + 0.01 * 3.0, 1e-12);
}

TEST(Prbs, RejectsBadArguments) {
  EXPECT_THROW(MaximalLengthSequence(1), std::invalid_argument);
  EXPECT_THROW(MaximalLengthSequence(32), std::invalid_argument);
  EXPECT_THROW(MaximalLengthSequence(4, 0), std::invalid_argument);
  EXPECT_THROW(MaximalLengthSequence(4, 16), std::invalid_argument);  // does not fit in 4 bits
  PrbsSignalSpec spec;
  spec.amplitude = 0.0;
  EXPECT_THROW(GeneratePrbs(spec, 10), std::invalid_argument);
  spec.amplitude = 1.0;
  spec.clock_period_samples = 0;
  EXPECT_THROW(GeneratePrbs(spec, 10), std::invalid_argument);
  spec.clock_period_samples = 1;
  EXPECT_THROW(GeneratePrbs(spec, -1), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
