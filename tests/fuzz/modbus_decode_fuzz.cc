// Modbus replies as the poller turns them into channel values (drivers/modbus/plc_poller.cc):
// the bytes give a PLC's channels (register kind, address, type, word order, scaling), the read
// gap and block limits, then the register words of the replies.  The channels are planned with
// PlanReads, each channel's registers are taken from its block's reply exactly as the poller
// takes them (without bounds checks, so the plan must be right), and decoded with
// drivers::DecodeChannel.  Properties: the plan covers every channel inside one block of its kind,
// blocks respect the Modbus limit, a valid value is finite and in range and encodes back.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <span>
#include <stdexcept>
#include <vector>

#include "drivers/modbus/channel_scaling.h"
#include "drivers/modbus/read_plan.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using canalid::fuzz::Check;
namespace drivers = canalid::drivers;

// Reads fixed-size values off the front of the input; zeros once it is used up.
class Bytes {
 public:
  Bytes(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T Take() {
    T value{};
    const std::size_t n = std::min(sizeof(T), size_ - used_);
    if (n > 0) std::memcpy(&value, data_ + used_, n);
    used_ += n;
    return value;
  }
  bool empty() const { return used_ == size_; }

 private:
  const uint8_t* data_;
  std::size_t size_;
  std::size_t used_ = 0;
};

struct Channel {
  drivers::RegisterSpan span;
  drivers::ChannelScaling scaling;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in(data, size);
  const int max_gap = in.Take<uint8_t>() % 40 - 4;  // -4..35: some invalid
  const int max_block = in.Take<uint8_t>() % (drivers::kMaxReadRegisters + 5);  // 0..129
  const int count = in.Take<uint8_t>() % 33;
  std::vector<Channel> channels;
  for (int i = 0; i < count; ++i) {
    Channel c;
    const auto layout = in.Take<uint8_t>();
    c.span.kind =
        (layout & 1) != 0 ? drivers::RegisterKind::kInput : drivers::RegisterKind::kHolding;
    c.scaling.type = static_cast<drivers::RegisterType>((layout >> 1) % 5);
    c.scaling.word_order =
        (layout & 16) != 0 ? drivers::WordOrder::kLowWordFirst : drivers::WordOrder::kHighWordFirst;
    c.span.count = drivers::RegisterCount(c.scaling.type);
    // Mostly addresses near each other (so blocks merge), sometimes anywhere (even invalid).
    const auto address = in.Take<uint16_t>();
    c.span.address = (layout & 32) != 0 ? address % 300 : static_cast<int>(address) + 1;
    if ((layout & 64) != 0) {
      c.scaling.scale = in.Take<double>();
      c.scaling.offset = in.Take<double>();
      c.scaling.min_value = in.Take<double>();
      c.scaling.max_value = in.Take<double>();
    } else {
      c.scaling.scale = 0.001 * (in.Take<int8_t>() | 1);
      c.scaling.min_value = -in.Take<uint8_t>();
      c.scaling.max_value = in.Take<uint8_t>();
    }
    try {
      drivers::ValidateChannelScaling(c.scaling);
    } catch (const std::invalid_argument&) {
      continue;  // the daemon rejects the configuration
    }
    channels.push_back(c);
  }
  std::vector<drivers::RegisterSpan> spans;
  spans.reserve(channels.size());
  for (const Channel& c : channels) spans.push_back(c.span);
  drivers::ReadPlan plan;
  try {
    plan = drivers::PlanReads(spans, max_gap, max_block);
  } catch (const std::invalid_argument&) {
    return 0;  // the daemon rejects the configuration
  }
  Check(plan.channels.size() == channels.size(), "one location per channel");
  int total = 0;
  std::vector<int> block_offsets;
  for (const drivers::ReadBlock& b : plan.blocks) {
    Check(b.count >= 1 && b.count <= max_block && b.count <= drivers::kMaxReadRegisters,
          "a block is a legal Modbus read");
    Check(b.start >= 0 && b.start + b.count <= 65536, "a block lies in the address space");
    block_offsets.push_back(total);
    total += b.count;
  }
  Check(total == plan.total_registers, "total_registers is the sum of the blocks");
  // The replies: one register image for all blocks, as the poller keeps it.
  std::vector<uint16_t> image(static_cast<std::size_t>(total));
  for (uint16_t& word : image) word = in.Take<uint16_t>();
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const Channel& c = channels[i];
    const drivers::ChannelLocation& loc = plan.channels[i];
    Check(loc.block >= 0 && loc.block < static_cast<int>(plan.blocks.size()),
          "a channel's block exists");
    const drivers::ReadBlock& b = plan.blocks[static_cast<std::size_t>(loc.block)];
    Check(b.kind == c.span.kind, "a channel is read with its register kind");
    Check(loc.offset >= 0 && loc.offset + c.span.count <= b.count,
          "a channel's registers are inside its block");
    Check(b.start + loc.offset == c.span.address, "a channel is read at its address");
    const std::span<const uint16_t> registers(
        image.data() + block_offsets[static_cast<std::size_t>(loc.block)] + loc.offset,
        static_cast<std::size_t>(c.span.count));
    const drivers::DecodedValue d = drivers::DecodeChannel(c.scaling, registers);
    Check(d.error != drivers::ScalingError::kWrongRegisterCount, "the channel's register count");
    if (d.ok()) {
      Check(std::isfinite(d.value), "a valid value is finite");
      Check(d.value >= c.scaling.min_value && d.value <= c.scaling.max_value,
            "a valid value is in range");
      uint16_t back[2] = {0, 0};
      const drivers::ScalingError e = drivers::EncodeChannel(
          c.scaling, d.value, std::span<uint16_t>(back, static_cast<std::size_t>(c.span.count)));
      Check(e == drivers::ScalingError::kNone || e == drivers::ScalingError::kNotRepresentable,
            "a valid value encodes (or its raw value does not fit the register type)");
    } else if (d.error == drivers::ScalingError::kOutOfRange) {
      Check(std::isfinite(d.value) &&
                (d.value < c.scaling.min_value || d.value > c.scaling.max_value),
            "an out-of-range value is finite and outside the range");
    }
  }
  return 0;
}
