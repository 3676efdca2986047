// LagLine against RingBuffer (the ring without the mirror) fed the same values.
#include "core/numerics/lag_line.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "core/numerics/ring_buffer.h"

namespace canalid::core {
namespace {

// Every lag reads what RingBuffer reads, at every position of the ring (several wraps), and the
// lags form one array: Lags()[lag] for the whole capacity, no wrap in between.
TEST(LagLine, EveryLagIsTheValuePushedThatManyPushesAgo) {
  for (const int capacity : {1, 2, 5, 8}) {
    LagLine line(capacity);
    RingBuffer<double> ring(capacity);
    for (int k = 0; k < 4 * capacity + 3; ++k) {
      const double value = 0.5 * k - 3.0;
      line.Push(value);
      ring.Push(value);
      const double* lags = line.Lags();
      for (int lag = 0; lag < capacity; ++lag) {
        const double want = lag < ring.size() ? ring[lag] : 0.0;  // not yet pushed: 0
        ASSERT_EQ(lags[lag], want) << "capacity " << capacity << " k " << k << " lag " << lag;
        ASSERT_EQ(line[lag], want);
      }
    }
  }
}

TEST(LagLine, ResetForgetsEveryValue) {
  LagLine line(3);
  for (int k = 1; k <= 4; ++k) line.Push(k);
  line.Reset();
  for (int lag = 0; lag < 3; ++lag) EXPECT_EQ(line[lag], 0.0);
  line.Push(7.0);
  EXPECT_EQ(line[0], 7.0);
  EXPECT_EQ(line[1], 0.0);
}

TEST(LagLine, RefusesAnEmptyLine) {
  EXPECT_THROW(LagLine(0), std::invalid_argument);
  EXPECT_EQ(LagLine(4).capacity(), 4);
}

}  // namespace
}  // namespace canalid::core
