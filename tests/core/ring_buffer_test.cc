// RingBuffer: lags and the chronological runs of storage, checked against a plain history.
#include "core/numerics/ring_buffer.h"

#include <gtest/gtest.h>

#include <vector>

namespace canalid::core {
namespace {

// The runs concatenated, oldest first.
std::vector<int> Concatenated(const RingBuffer<int>::Runs& runs) {
  std::vector<int> v(runs.older.begin(), runs.older.end());
  v.insert(v.end(), runs.newer.begin(), runs.newer.end());
  return v;
}

TEST(RingBuffer, ChronologicalRunsAreTheNewestValuesOldestFirst) {
  RingBuffer<int> ring(5);
  std::vector<int> pushed;
  for (int value = 1; value <= 13; ++value) {  // fills, then wraps at every position
    ring.Push(value);
    pushed.push_back(value);
    for (int count = 0; count <= ring.size(); ++count) {
      const std::vector<int> want(pushed.end() - count, pushed.end());
      const RingBuffer<int>::Runs runs = ring.Chronological(count);
      EXPECT_EQ(Concatenated(runs), want) << "after " << value << ", count " << count;
      // At most one wrap: the newer run starts the storage when there are two.
      if (!runs.older.empty()) {
        EXPECT_FALSE(runs.newer.empty());
      }
      for (int lag = 0; lag < count; ++lag) {
        EXPECT_EQ(ring[lag], want[want.size() - 1 - static_cast<std::size_t>(lag)]);
      }
    }
  }
}

TEST(RingBuffer, EmptyHasNoRuns) {
  RingBuffer<double> ring(3);
  const RingBuffer<double>::Runs runs = ring.Chronological(0);
  EXPECT_TRUE(runs.older.empty());
  EXPECT_TRUE(runs.newer.empty());
  EXPECT_THROW(RingBuffer<double>(0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
