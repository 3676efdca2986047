#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace canalid::core {

/// How a 32-bit value is laid out over two 16-bit Modbus registers.  Its bytes from most to least
/// significant are A B C D; the letters give them in register order (register n high byte,
/// register n low byte, register n+1 high byte, register n+1 low byte).
///   kHighWordFirst: ABCD, register[0] holds bits 31..16 (Modbus "big endian", Schneider
///                   "swap off").
///   kLowWordFirst:  CDAB, register[0] holds bits 15..0 (word swap; many Siemens/Modicon maps).
///   kHighWordFirstByteSwapped, kLowWordFirstByteSwapped: BADC, DCBA (the bytes of each register
///                   swapped as well).
enum class WordOrder {
  kHighWordFirst,
  kLowWordFirst,
  kHighWordFirstByteSwapped,
  kLowWordFirstByteSwapped
};

/// "abcd", "cdab", "badc" or "dcba" (the byte letters above).
std::string_view WordOrderLetters(WordOrder order);
/// Inverse of WordOrderLetters; nullopt for any other text.
std::optional<WordOrder> WordOrderFromLetters(std::string_view letters);

/// A 32-bit pattern written to / read from registers[0], registers[1] in the given order.
/// Pure, no allocation.
void EncodeUint32(std::uint32_t value, WordOrder order, std::span<std::uint16_t, 2> registers);
std::uint32_t DecodeUint32(std::span<const std::uint16_t, 2> registers, WordOrder order);

/// Two's complement signed 32-bit integer over two registers.
void EncodeInt32(std::int32_t value, WordOrder order, std::span<std::uint16_t, 2> registers);
std::int32_t DecodeInt32(std::span<const std::uint16_t, 2> registers, WordOrder order);

/// IEEE 754 binary32 bit pattern over two registers.
void EncodeFloat32(float value, WordOrder order, std::span<std::uint16_t, 2> registers);
float DecodeFloat32(std::span<const std::uint16_t, 2> registers, WordOrder order);

/// Signed 16-bit integer as its two's complement in one register.
std::uint16_t EncodeInt16(std::int16_t value);
std::int16_t DecodeInt16(std::uint16_t word);

/// A value as a signed 16-bit scaled integer: count = round(value / unit), saturated to
/// [-32768, 32767], stored as its two's complement.  NaN encodes as -32768 (the "bad value"
/// marker of many PLCs).  @pre unit > 0.
std::uint16_t EncodeScaled16(double value, double unit);
/// Inverse of EncodeScaled16: value = int16(count) * unit (a NaN marker decodes as -32768 unit).
double DecodeScaled16(std::uint16_t count, double unit);

}  // namespace canalid::core
