#pragma once
#include <cstdint>
#include <span>

#include "core/registers/register_codec.h"

namespace canalid::drivers {

using core::WordOrder;

/// How a channel's raw value is laid out in 16-bit Modbus registers.
///   kU16, kI16: one register (unsigned, two's complement).
///   kU32, kI32: two registers forming a 32-bit integer.
///   kF32: two registers forming an IEEE 754 binary32 bit pattern.
enum class RegisterType { kU16, kI16, kU32, kI32, kF32 };

/// WordOrder (core/registers/register_codec.h): the order of the two 16-bit words of a 32-bit
/// value.

/// Number of registers a type occupies (1 or 2).
int RegisterCount(RegisterType type);

/// Linear scaling and validity range of one channel:
///   engineering = raw * scale + offset,   valid iff min_value <= engineering <= max_value.
/// Units are the channel's (e.g. level_m); raw is the integer or float read from the registers.
struct ChannelScaling {
  RegisterType type = RegisterType::kU16;
  WordOrder word_order = WordOrder::kHighWordFirst;
  double scale = 1.0;
  double offset = 0.0;
  double min_value = -1e300;
  double max_value = 1e300;
};

/// Throws std::invalid_argument naming the field when scale is zero or not finite, offset is not
/// finite, min_value > max_value, or a bound is NaN.
void ValidateChannelScaling(const ChannelScaling& scaling);

/// Why a conversion produced no value. Never thrown: returned on the sample path.
enum class ScalingError {
  kNone,
  kWrongRegisterCount,  ///< span size differs from RegisterCount(type)
  kNotFinite,           ///< a float register pattern is NaN or infinite, or the input is
  kOutOfRange,          ///< engineering value outside [min_value, max_value]
  kNotRepresentable,    ///< the raw value for an engineering value overflows the register type
};

/// Result of DecodeChannel: `value` is meaningful only when error == kNone, except for
/// kOutOfRange, where it holds the decoded (out of range) engineering value for diagnostics.
struct DecodedValue {
  double value = 0.0;
  ScalingError error = ScalingError::kNone;
  bool ok() const { return error == ScalingError::kNone; }
};

/// The raw number held by `registers` (before scale and offset). kF32 returns the float value.
/// @pre registers.size() == RegisterCount(type) (else returns 0).
double RawFromRegisters(RegisterType type, WordOrder order, std::span<const uint16_t> registers);

/// registers -> engineering value, with range and finiteness checks. Pure, no allocation.
DecodedValue DecodeChannel(const ChannelScaling& scaling, std::span<const uint16_t> registers);

/// engineering value -> registers: raw = (value - offset) / scale, rounded to the nearest integer
/// for integer types (ties away from zero), checked against [min_value, max_value] first and then
/// against the type's range. On error `registers` is left untouched. Pure, no allocation.
ScalingError EncodeChannel(const ChannelScaling& scaling, double value,
                           std::span<uint16_t> registers);

/// Short English name of an error ("out of range" ...), for logs and reports.
const char* ScalingErrorName(ScalingError error);

}  // namespace canalid::drivers
