#include "core/numerics/splitmix64.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace canalid::core {
namespace {

// The reference outputs of Vigna's splitmix64.c from state 0 (0xE220A8397B1DCDAF =
// 16294208416658607535 is the widely quoted first value).
TEST(SplitMix64, MatchesTheReferenceOutputsFromZero) {
  SplitMix64 random(0);
  EXPECT_EQ(random.Next(), 0xE220A8397B1DCDAFULL);
  EXPECT_EQ(random.Next(), 0x6E789E6AA1B965F4ULL);
  EXPECT_EQ(random.Next(), 0x06C45D188009454FULL);
  static_assert(SplitMix64Hash(0) == 0xE220A8397B1DCDAFULL);
}

TEST(SplitMix64, UniformIsInTheUnitIntervalWithMeanOneHalf) {
  SplitMix64 random(42);
  double sum = 0.0;
  constexpr int kCount = 100000;
  for (int k = 0; k < kCount; ++k) {
    const double u = random.NextUniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
  }
  // Standard error of the mean: 1 / sqrt(12 n) = 0.0009.
  EXPECT_NEAR(sum / kCount, 0.5, 0.005);
}

}  // namespace
}  // namespace canalid::core
