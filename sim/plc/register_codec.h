#pragma once
#include <cstdint>
#include <string_view>

namespace canalid::sim::plc {

/// How a 32-bit IEEE-754 float is laid out over two 16-bit Modbus registers.  The float's bytes
/// from most to least significant are A B C D; the name gives them in register order (register n
/// high byte, register n low byte, register n+1 high byte, register n+1 low byte).
///  - kAbcd: big-endian, high word first (Modbus convention, Schneider "swap off").
///  - kCdab: low word first (word swap; many Siemens/Modicon-style maps).
///  - kBadc, kDcba: byte-swapped variants of the two above.
enum class WordOrder { kAbcd, kCdab, kBadc, kDcba };

/// Parses "abcd", "cdab", "badc" or "dcba".  @returns false for anything else.
bool ParseWordOrder(std::string_view text, WordOrder* order);
std::string_view WordOrderName(WordOrder order);

/// A value as a signed 16-bit scaled integer: count = round(value / unit), saturated to
/// [-32768, 32767], stored as its two's complement.  NaN encodes as -32768 (the "bad value"
/// marker of many PLCs).  @pre unit > 0.
std::uint16_t EncodeScaled16(double value, double unit);
/// Inverse of EncodeScaled16: value = int16(count) * unit (a NaN marker decodes as -32768 unit).
double DecodeScaled16(std::uint16_t count, double unit);

/// Writes `value` (as float) to out[0], out[1] in the given order.
void EncodeFloat32(float value, WordOrder order, std::uint16_t* out);
/// Reads the float stored in in[0], in[1] in the given order.
float DecodeFloat32(const std::uint16_t* in, WordOrder order);

/// An unsigned 32-bit integer over two registers, high word first.
void EncodeUint32(std::uint32_t value, std::uint16_t* out);
std::uint32_t DecodeUint32(const std::uint16_t* in);

}  // namespace canalid::sim::plc
