#include "sim/plc/register_codec.h"

#include <bit>
#include <cmath>

namespace canalid::sim::plc {

bool ParseWordOrder(std::string_view text, WordOrder* order) {
  if (text == "abcd") {
    *order = WordOrder::kAbcd;
  } else if (text == "cdab") {
    *order = WordOrder::kCdab;
  } else if (text == "badc") {
    *order = WordOrder::kBadc;
  } else if (text == "dcba") {
    *order = WordOrder::kDcba;
  } else {
    return false;
  }
  return true;
}

std::string_view WordOrderName(WordOrder order) {
  switch (order) {
    case WordOrder::kAbcd:
      return "abcd";
    case WordOrder::kCdab:
      return "cdab";
    case WordOrder::kBadc:
      return "badc";
    case WordOrder::kDcba:
      return "dcba";
  }
  return "?";
}

std::uint16_t EncodeScaled16(double value, double unit) {
  if (std::isnan(value)) return 0x8000;
  const double count = std::round(value / unit);
  const double saturated = count < -32768.0 ? -32768.0 : (count > 32767.0 ? 32767.0 : count);
  return static_cast<std::uint16_t>(static_cast<std::int16_t>(saturated));
}

double DecodeScaled16(std::uint16_t count, double unit) {
  return static_cast<double>(static_cast<std::int16_t>(count)) * unit;
}

namespace {
std::uint16_t SwapBytes(std::uint16_t w) { return static_cast<std::uint16_t>((w >> 8) | (w << 8)); }
}  // namespace

void EncodeFloat32(float value, WordOrder order, std::uint16_t* out) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  const auto high = static_cast<std::uint16_t>(bits >> 16);     // bytes A B
  const auto low = static_cast<std::uint16_t>(bits & 0xFFFFu);  // bytes C D
  switch (order) {
    case WordOrder::kAbcd:
      out[0] = high;
      out[1] = low;
      break;
    case WordOrder::kCdab:
      out[0] = low;
      out[1] = high;
      break;
    case WordOrder::kBadc:
      out[0] = SwapBytes(high);
      out[1] = SwapBytes(low);
      break;
    case WordOrder::kDcba:
      out[0] = SwapBytes(low);
      out[1] = SwapBytes(high);
      break;
  }
}

float DecodeFloat32(const std::uint16_t* in, WordOrder order) {
  std::uint16_t high = 0;
  std::uint16_t low = 0;
  switch (order) {
    case WordOrder::kAbcd:
      high = in[0];
      low = in[1];
      break;
    case WordOrder::kCdab:
      low = in[0];
      high = in[1];
      break;
    case WordOrder::kBadc:
      high = SwapBytes(in[0]);
      low = SwapBytes(in[1]);
      break;
    case WordOrder::kDcba:
      low = SwapBytes(in[0]);
      high = SwapBytes(in[1]);
      break;
  }
  return std::bit_cast<float>((static_cast<std::uint32_t>(high) << 16) | low);
}

void EncodeUint32(std::uint32_t value, std::uint16_t* out) {
  out[0] = static_cast<std::uint16_t>(value >> 16);
  out[1] = static_cast<std::uint16_t>(value & 0xFFFFu);
}

std::uint32_t DecodeUint32(const std::uint16_t* in) {
  return (static_cast<std::uint32_t>(in[0]) << 16) | in[1];
}

}  // namespace canalid::sim::plc
