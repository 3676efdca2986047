#include "sim/prbs_sequence.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace canalid::sim {
namespace {

// Maximal length: period 2^n - 1, one more +1 than -1, and a circular autocorrelation of -1 at
// every non-zero lag (the two-valued autocorrelation of m-sequences).
TEST(PrbsSequence, IsMaximalLengthForEveryOrder) {
  for (int n = 2; n <= 16; ++n) {
    const std::vector<int> s = PrbsSequence(n, 12345);
    const int period = (1 << n) - 1;
    ASSERT_EQ(static_cast<int>(s.size()), period) << n;
    int sum = 0;
    for (int v : s) sum += v;
    EXPECT_EQ(sum, 1) << "order " << n;
    for (int lag : {1, 2, period / 2, period - 1}) {
      if (lag <= 0 || lag >= period) continue;
      int r = 0;
      for (int k = 0; k < period; ++k) r += s[k] * s[(k + lag) % period];
      EXPECT_EQ(r, -1) << "order " << n << " lag " << lag;
    }
  }
}

TEST(PrbsSequence, SeedShiftsTheSequenceAndBadOrderThrows) {
  const std::vector<int> a = PrbsSequence(7, 1), b = PrbsSequence(7, 2);
  EXPECT_NE(a, b);
  EXPECT_EQ(a, PrbsSequence(7, 1));
  EXPECT_THROW(PrbsSequence(1, 1), std::invalid_argument);
  EXPECT_THROW(PrbsSequence(17, 1), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::sim
