#include "drivers/modbus/channel_scaling.h"

#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::drivers {
namespace {

// @pre r.size() == 2 (checked by the callers).
uint32_t Combine(WordOrder order, std::span<const uint16_t> r) {
  return DecodeUint32(r.first<2>(), order);
}

void Split(WordOrder order, uint32_t bits, std::span<uint16_t> r) {
  EncodeUint32(bits, order, r.first<2>());
}

}  // namespace

int RegisterCount(RegisterType type) {
  return type == RegisterType::kU16 || type == RegisterType::kI16 ? 1 : 2;
}

void ValidateChannelScaling(const ChannelScaling& s) {
  if (!std::isfinite(s.scale) || s.scale == 0.0) {
    throw std::invalid_argument("channel scaling: scale = " + std::to_string(s.scale) +
                                " must be finite and non-zero");
  }
  if (!std::isfinite(s.offset)) {
    throw std::invalid_argument("channel scaling: offset = " + std::to_string(s.offset) +
                                " must be finite");
  }
  if (std::isnan(s.min_value) || std::isnan(s.max_value) || s.min_value > s.max_value) {
    throw std::invalid_argument("channel scaling: min_value = " + std::to_string(s.min_value) +
                                " must be <= max_value = " + std::to_string(s.max_value));
  }
}

double RawFromRegisters(RegisterType type, WordOrder order, std::span<const uint16_t> r) {
  if (static_cast<int>(r.size()) != RegisterCount(type)) return 0.0;
  switch (type) {
    case RegisterType::kU16:
      return r[0];
    case RegisterType::kI16:
      return static_cast<int16_t>(r[0]);
    case RegisterType::kU32:
      return Combine(order, r);
    case RegisterType::kI32:
      return static_cast<int32_t>(Combine(order, r));
    case RegisterType::kF32:
      return std::bit_cast<float>(Combine(order, r));
  }
  return 0.0;
}

DecodedValue DecodeChannel(const ChannelScaling& s, std::span<const uint16_t> registers) {
  if (static_cast<int>(registers.size()) != RegisterCount(s.type)) {
    return {0.0, ScalingError::kWrongRegisterCount};
  }
  const double value = RawFromRegisters(s.type, s.word_order, registers) * s.scale + s.offset;
  if (!std::isfinite(value)) return {0.0, ScalingError::kNotFinite};
  if (value < s.min_value || value > s.max_value) return {value, ScalingError::kOutOfRange};
  return {value, ScalingError::kNone};
}

ScalingError EncodeChannel(const ChannelScaling& s, double value, std::span<uint16_t> registers) {
  if (static_cast<int>(registers.size()) != RegisterCount(s.type)) {
    return ScalingError::kWrongRegisterCount;
  }
  if (!std::isfinite(value)) return ScalingError::kNotFinite;
  if (value < s.min_value || value > s.max_value) return ScalingError::kOutOfRange;
  const double raw = (value - s.offset) / s.scale;
  if (s.type == RegisterType::kF32) {
    const auto f = static_cast<float>(raw);
    if (!std::isfinite(f)) return ScalingError::kNotRepresentable;
    Split(s.word_order, std::bit_cast<uint32_t>(f), registers);
    return ScalingError::kNone;
  }
  const double rounded = std::round(raw);
  double low = 0.0;
  double high = 0.0;
  switch (s.type) {
    case RegisterType::kU16:
      high = 65535.0;
      break;
    case RegisterType::kI16:
      low = -32768.0;
      high = 32767.0;
      break;
    case RegisterType::kU32:
      high = 4294967295.0;
      break;
    case RegisterType::kI32:
      low = -2147483648.0;
      high = 2147483647.0;
      break;
    case RegisterType::kF32:
      break;
  }
  if (!(rounded >= low && rounded <= high)) return ScalingError::kNotRepresentable;
  if (s.type == RegisterType::kU16 || s.type == RegisterType::kI16) {
    // Two's complement of the 16-bit value, computed without implementation-defined casts.
    const auto as_int = static_cast<int32_t>(rounded);
    registers[0] = static_cast<uint16_t>(static_cast<uint32_t>(as_int) & 0xFFFFu);
    return ScalingError::kNone;
  }
  const auto bits = s.type == RegisterType::kU32
                        ? static_cast<uint32_t>(rounded)
                        : static_cast<uint32_t>(static_cast<int32_t>(rounded));
  Split(s.word_order, bits, registers);
  return ScalingError::kNone;
}

const char* ScalingErrorName(ScalingError error) {
  switch (error) {
    case ScalingError::kNone:
      return "ok";
    case ScalingError::kWrongRegisterCount:
      return "wrong register count";
    case ScalingError::kNotFinite:
      return "not finite";
    case ScalingError::kOutOfRange:
      return "out of range";
    case ScalingError::kNotRepresentable:
      return "not representable";
  }
  return "unknown";
}

}  // namespace canalid::drivers
