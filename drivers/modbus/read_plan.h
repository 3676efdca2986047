#pragma once
#include <span>
#include <vector>

#include "drivers/modbus/plc_port.h"

namespace canalid::drivers {

/// The registers one channel occupies.
struct RegisterSpan {
  RegisterKind kind = RegisterKind::kHolding;
  int address = 0;  ///< 0-based, 0..65535
  int count = 1;    ///< 1..max_block_registers (1 or 2 for our channel types)
};

/// One Modbus read request of the plan.
struct ReadBlock {
  RegisterKind kind = RegisterKind::kHolding;
  int start = 0;
  int count = 0;
};

/// Where channel i's registers are in the plan: block `block`, first register at `offset`.
struct ChannelLocation {
  int block = 0;
  int offset = 0;
};

struct ReadPlan {
  std::vector<ReadBlock> blocks;
  std::vector<ChannelLocation> channels;  ///< same order as the input channels
  int total_registers = 0;                ///< sum of block counts (registers moved per poll)
};

/// Groups channels into as few reads as a greedy sweep gives: channels are sorted by (kind,
/// address); a channel joins the current block when it has the same kind, starts at most
/// `max_gap_registers` unused registers after the block's end (overlaps allowed), and the block
/// would stay within `max_block_registers`. Otherwise it starts a new block. Gap registers are
/// read and ignored, trading a few bytes for a request round trip. Computed once at start.
/// @throws std::invalid_argument when a channel is outside 0..65535, count is not in
///   1..max_block_registers, max_gap_registers < 0, or max_block_registers is not in 1..125.
ReadPlan PlanReads(std::span<const RegisterSpan> channels, int max_gap_registers,
                   int max_block_registers = kMaxReadRegisters);

}  // namespace canalid::drivers
