#include "drivers/modbus/read_plan.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

namespace canalid::drivers {
namespace {

using enum RegisterKind;

TEST(ModbusReadPlan, MergesContiguousAndNearbyRegistersOfOneKind) {
  // Holding 0 (1), 1 (2), 10 (1) with gap 7: 10 - 3 = 7 unused registers, merged: one read 0..10.
  // Input 0 (1) is another table: its own read.
  const std::vector<RegisterSpan> channels = {
      {kHolding, 10, 1}, {kInput, 0, 1}, {kHolding, 0, 1}, {kHolding, 1, 2}};
  const ReadPlan plan = PlanReads(channels, 7);
  ASSERT_EQ(plan.blocks.size(), 2u);
  EXPECT_EQ(plan.blocks[0].kind, kHolding);
  EXPECT_EQ(plan.blocks[0].start, 0);
  EXPECT_EQ(plan.blocks[0].count, 11);
  EXPECT_EQ(plan.blocks[1].kind, kInput);
  EXPECT_EQ(plan.blocks[1].count, 1);
  EXPECT_EQ(plan.channels[0].block, 0);
  EXPECT_EQ(plan.channels[0].offset, 10);
  EXPECT_EQ(plan.channels[1].block, 1);
  EXPECT_EQ(plan.channels[3].offset, 1);
  EXPECT_EQ(plan.total_registers, 12);

  // One register less of allowed gap splits the holding block.
  const ReadPlan tight = PlanReads(channels, 6);
  ASSERT_EQ(tight.blocks.size(), 3u);
  EXPECT_EQ(tight.blocks[0].count, 3);
  EXPECT_EQ(tight.blocks[1].start, 10);
}

TEST(ModbusReadPlan, NeverExceeds125Registers) {
  // 130 contiguous u16 channels: 125 + 5. A 2-register channel at 124 cannot straddle the limit.
  std::vector<RegisterSpan> channels;
  channels.reserve(130);
  for (int a = 0; a < 130; ++a) channels.push_back({kInput, a, 1});
  ReadPlan plan = PlanReads(channels, 0);
  ASSERT_EQ(plan.blocks.size(), 2u);
  EXPECT_EQ(plan.blocks[0].count, 125);
  EXPECT_EQ(plan.blocks[1].start, 125);
  EXPECT_EQ(plan.blocks[1].count, 5);

  const std::vector<RegisterSpan> straddle = {{kHolding, 0, 1}, {kHolding, 124, 2}};
  plan = PlanReads(straddle, 200);
  ASSERT_EQ(plan.blocks.size(), 2u);
  EXPECT_EQ(plan.blocks[1].start, 124);
  EXPECT_EQ(plan.blocks[1].count, 2);
}

TEST(ModbusReadPlan, OverlappingChannelsShareRegisters) {
  // The same register seen as u16 and as the first word of an f32.
  const std::vector<RegisterSpan> channels = {{kHolding, 5, 2}, {kHolding, 5, 1}};
  const ReadPlan plan = PlanReads(channels, 0);
  ASSERT_EQ(plan.blocks.size(), 1u);
  EXPECT_EQ(plan.blocks[0].count, 2);
  EXPECT_EQ(plan.channels[0].offset, 0);
  EXPECT_EQ(plan.channels[1].offset, 0);
}

// Property check on random maps: each channel's registers lie inside its block, blocks are of the
// channel's kind and within 125, and no two blocks of one kind could have been one read.
TEST(ModbusReadPlan, RandomMapsSatisfyThePlanInvariants) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<RegisterSpan> channels;
    const int n = std::uniform_int_distribution<int>(1, 60)(rng);
    channels.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      channels.push_back({rng() % 2 ? kHolding : kInput,
                          std::uniform_int_distribution<int>(0, 600)(rng),
                          std::uniform_int_distribution<int>(1, 2)(rng)});
    }
    const int gap = std::uniform_int_distribution<int>(0, 20)(rng);
    const ReadPlan plan = PlanReads(channels, gap);
    for (std::size_t i = 0; i < channels.size(); ++i) {
      const ReadBlock& b = plan.blocks.at(static_cast<std::size_t>(plan.channels[i].block));
      EXPECT_EQ(b.kind, channels[i].kind);
      EXPECT_EQ(b.start + plan.channels[i].offset, channels[i].address);
      EXPECT_LE(plan.channels[i].offset + channels[i].count, b.count);
    }
    for (std::size_t k = 0; k < plan.blocks.size(); ++k) {
      EXPECT_GE(plan.blocks[k].count, 1);
      EXPECT_LE(plan.blocks[k].count, 125);
      if (k > 0 && plan.blocks[k].kind == plan.blocks[k - 1].kind) {
        const ReadBlock& a = plan.blocks[k - 1];
        const ReadBlock& b = plan.blocks[k];
        const bool too_far = b.start - (a.start + a.count) > gap;
        const bool too_long = std::max(a.start + a.count, b.start + b.count) - a.start > 125;
        EXPECT_TRUE(too_far || too_long) << "blocks " << k - 1 << " and " << k << " mergeable";
      }
    }
  }
}

TEST(ModbusReadPlan, RejectsBadChannels) {
  const std::vector<RegisterSpan> past_end = {{kHolding, 65535, 2}};
  EXPECT_THROW(PlanReads(past_end, 0), std::invalid_argument);
  const std::vector<RegisterSpan> negative = {{kHolding, -1, 1}};
  EXPECT_THROW(PlanReads(negative, 0), std::invalid_argument);
  const std::vector<RegisterSpan> ok = {{kHolding, 0, 1}};
  EXPECT_THROW(PlanReads(ok, -1), std::invalid_argument);
  EXPECT_THROW(PlanReads(ok, 0, 126), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::drivers
