#include "drivers/modbus/read_plan.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace canalid::drivers {

ReadPlan PlanReads(std::span<const RegisterSpan> channels, int max_gap_registers,
                   int max_block_registers) {
  if (max_block_registers < 1 || max_block_registers > kMaxReadRegisters) {
    throw std::invalid_argument("read plan: max_block_registers = " +
                                std::to_string(max_block_registers) + " outside [1, 125]");
  }
  if (max_gap_registers < 0) {
    throw std::invalid_argument(
        "read plan: max_gap_registers = " + std::to_string(max_gap_registers) + " must be >= 0");
  }
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const RegisterSpan& c = channels[i];
    if (c.count < 1 || c.count > max_block_registers || c.address < 0 ||
        c.address + c.count > 65536) {
      throw std::invalid_argument("read plan: channel " + std::to_string(i) + " at address " +
                                  std::to_string(c.address) + " with " + std::to_string(c.count) +
                                  " registers is outside 0..65535 or exceeds " +
                                  std::to_string(max_block_registers) + " registers");
    }
  }
  std::vector<std::size_t> order(channels.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (channels[a].kind != channels[b].kind) return channels[a].kind < channels[b].kind;
    return channels[a].address < channels[b].address;
  });

  ReadPlan plan;
  plan.channels.resize(channels.size());
  for (std::size_t i : order) {
    const RegisterSpan& c = channels[i];
    const int end = c.address + c.count;
    bool joined = false;
    if (!plan.blocks.empty()) {
      ReadBlock& b = plan.blocks.back();
      const int block_end = b.start + b.count;
      const int new_end = std::max(block_end, end);
      if (b.kind == c.kind && c.address - block_end <= max_gap_registers &&
          new_end - b.start <= max_block_registers) {
        b.count = new_end - b.start;
        joined = true;
      }
    }
    if (!joined) plan.blocks.push_back({c.kind, c.address, c.count});
    plan.channels[i] = {static_cast<int>(plan.blocks.size()) - 1,
                        c.address - plan.blocks.back().start};
  }
  for (const ReadBlock& b : plan.blocks) plan.total_registers += b.count;
  return plan;
}

}  // namespace canalid::drivers
