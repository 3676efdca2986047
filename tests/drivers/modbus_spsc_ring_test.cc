#include "drivers/modbus/spsc_ring.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

namespace canalid::drivers {
namespace {

TEST(SpscRing, FillsToCapacityThenRefusesAndKeepsOrder) {
  SpscRing<int> ring(3, 0);
  EXPECT_EQ(ring.capacity(), 3u);
  EXPECT_EQ(ring.Front(), nullptr);
  for (int i = 1; i <= 3; ++i) {
    int* slot = ring.BeginPush();
    ASSERT_NE(slot, nullptr);
    *slot = i;
    ring.CommitPush();
  }
  EXPECT_EQ(ring.BeginPush(), nullptr);
  ASSERT_NE(ring.Front(), nullptr);
  EXPECT_EQ(*ring.Front(), 1);
  ring.Pop();
  int* slot = ring.BeginPush();
  ASSERT_NE(slot, nullptr);
  *slot = 4;
  ring.CommitPush();
  for (int expected = 2; expected <= 4; ++expected) {
    ASSERT_NE(ring.Front(), nullptr);
    EXPECT_EQ(*ring.Front(), expected);
    ring.Pop();
  }
  EXPECT_EQ(ring.Front(), nullptr);
}

// Two threads: every pushed slot's payload (a vector filled from its sequence number) arrives
// complete and in order. A torn or reordered slot would break the check; the run spins, so its
// length is bounded by the item count, not by time.
TEST(SpscRing, TwoThreadsSeeEveryItemCompleteAndInOrder) {
  constexpr int64_t kItems = 200000;
  SpscRing<std::vector<int64_t>> ring(8, std::vector<int64_t>(16, 0));
  std::thread producer([&] {
    for (int64_t i = 0; i < kItems;) {
      std::vector<int64_t>* slot = ring.BeginPush();
      if (slot == nullptr) {
        std::this_thread::yield();
        continue;
      }
      for (auto& x : *slot) x = i;
      ring.CommitPush();
      ++i;
    }
  });
  int64_t next = 0;
  int64_t bad = 0;
  while (next < kItems) {
    const std::vector<int64_t>* slot = ring.Front();
    if (slot == nullptr) {
      std::this_thread::yield();
      continue;
    }
    for (int64_t x : *slot) bad += x != next;
    ring.Pop();
    ++next;
  }
  producer.join();
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(ring.Front(), nullptr);
}

}  // namespace
}  // namespace canalid::drivers
