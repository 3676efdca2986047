#include "core/registers/register_codec.h"

#include <bit>
#include <cmath>

namespace canalid::core {
namespace {

std::uint16_t SwapBytes(std::uint16_t w) { return static_cast<std::uint16_t>((w >> 8) | (w << 8)); }

}  // namespace

std::string_view WordOrderLetters(WordOrder order) {
  switch (order) {
    case WordOrder::kHighWordFirst:
      return "abcd";
    case WordOrder::kLowWordFirst:
      return "cdab";
    case WordOrder::kHighWordFirstByteSwapped:
      return "badc";
    case WordOrder::kLowWordFirstByteSwapped:
      return "dcba";
  }
  return "?";
}

std::optional<WordOrder> WordOrderFromLetters(std::string_view letters) {
  for (WordOrder order :
       {WordOrder::kHighWordFirst, WordOrder::kLowWordFirst, WordOrder::kHighWordFirstByteSwapped,
        WordOrder::kLowWordFirstByteSwapped}) {
    if (letters == WordOrderLetters(order)) return order;
  }
  return std::nullopt;
}

void EncodeUint32(std::uint32_t value, WordOrder order, std::span<std::uint16_t, 2> out) {
  const auto high = static_cast<std::uint16_t>(value >> 16);     // bytes A B
  const auto low = static_cast<std::uint16_t>(value & 0xFFFFu);  // bytes C D
  switch (order) {
    case WordOrder::kHighWordFirst:
      out[0] = high;
      out[1] = low;
      break;
    case WordOrder::kLowWordFirst:
      out[0] = low;
      out[1] = high;
      break;
    case WordOrder::kHighWordFirstByteSwapped:
      out[0] = SwapBytes(high);
      out[1] = SwapBytes(low);
      break;
    case WordOrder::kLowWordFirstByteSwapped:
      out[0] = SwapBytes(low);
      out[1] = SwapBytes(high);
      break;
  }
}

std::uint32_t DecodeUint32(std::span<const std::uint16_t, 2> in, WordOrder order) {
  std::uint16_t high = 0;
  std::uint16_t low = 0;
  switch (order) {
    case WordOrder::kHighWordFirst:
      high = in[0];
      low = in[1];
      break;
    case WordOrder::kLowWordFirst:
      low = in[0];
      high = in[1];
      break;
    case WordOrder::kHighWordFirstByteSwapped:
      high = SwapBytes(in[0]);
      low = SwapBytes(in[1]);
      break;
    case WordOrder::kLowWordFirstByteSwapped:
      low = SwapBytes(in[0]);
      high = SwapBytes(in[1]);
      break;
  }
  return (static_cast<std::uint32_t>(high) << 16) | low;
}

void EncodeInt32(std::int32_t value, WordOrder order, std::span<std::uint16_t, 2> out) {
  EncodeUint32(std::bit_cast<std::uint32_t>(value), order, out);
}

std::int32_t DecodeInt32(std::span<const std::uint16_t, 2> in, WordOrder order) {
  return std::bit_cast<std::int32_t>(DecodeUint32(in, order));
}

void EncodeFloat32(float value, WordOrder order, std::span<std::uint16_t, 2> out) {
  EncodeUint32(std::bit_cast<std::uint32_t>(value), order, out);
}

float DecodeFloat32(std::span<const std::uint16_t, 2> in, WordOrder order) {
  return std::bit_cast<float>(DecodeUint32(in, order));
}

std::uint16_t EncodeInt16(std::int16_t value) { return std::bit_cast<std::uint16_t>(value); }

std::int16_t DecodeInt16(std::uint16_t word) { return std::bit_cast<std::int16_t>(word); }

std::uint16_t EncodeScaled16(double value, double unit) {
  if (std::isnan(value)) return 0x8000;
  const double count = std::round(value / unit);
  const double saturated = count < -32768.0 ? -32768.0 : (count > 32767.0 ? 32767.0 : count);
  return EncodeInt16(static_cast<std::int16_t>(saturated));
}

double DecodeScaled16(std::uint16_t count, double unit) {
  return static_cast<double>(DecodeInt16(count)) * unit;
}

}  // namespace canalid::core
