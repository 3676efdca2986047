// The register codec of the drivers and the emulated PLC, against hand-computed IEEE-754 bit
// patterns and libmodbus's own float helpers (an independent implementation).
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/registers/register_codec.h"

namespace canalid::core {
namespace {

TEST(Scaled16, RoundsToTheNearestCount) {
  EXPECT_EQ(EncodeScaled16(2.1, 0.001), 2100);
  EXPECT_EQ(EncodeScaled16(1.53264, 0.001), 1533);
  EXPECT_EQ(EncodeScaled16(11.0, 0.001), 11000);
  EXPECT_EQ(EncodeScaled16(0.00049, 0.001), 0);
}

TEST(Scaled16, NegativeValuesAreTwosComplement) {
  EXPECT_EQ(EncodeScaled16(-0.5, 0.001), 0xFE0C);  // -500 = 65536 - 500
  EXPECT_EQ(EncodeScaled16(-0.001, 0.001), 0xFFFF);
  EXPECT_DOUBLE_EQ(DecodeScaled16(0xFE0C, 0.001), -0.5);
  EXPECT_DOUBLE_EQ(DecodeScaled16(0xFFFF, 0.001), -0.001);
}

TEST(Scaled16, SaturatesAndMarksNaN) {
  EXPECT_EQ(EncodeScaled16(40.0, 0.001), 0x7FFF);
  EXPECT_EQ(EncodeScaled16(-40.0, 0.001), 0x8000);
  EXPECT_EQ(EncodeScaled16(std::numeric_limits<double>::quiet_NaN(), 0.001), 0x8000);
  EXPECT_DOUBLE_EQ(DecodeScaled16(0x7FFF, 0.001), 32.767);
  EXPECT_DOUBLE_EQ(DecodeScaled16(0x8000, 0.001), -32.768);
}

TEST(Scaled16, RoundTripWithinHalfACount) {
  for (double v = -30.0; v <= 30.0; v += 0.0137) {
    // Rounding to the nearest count loses at most half a count (plus float noise).
    EXPECT_NEAR(DecodeScaled16(EncodeScaled16(v, 0.001), 0.001), v, 0.0005 + 1e-12) << v;
  }
}

TEST(Float32, KnownBitPatterns) {
  std::uint16_t r[2];
  EncodeFloat32(1.0f, WordOrder::kHighWordFirst, r);  // 0x3F800000
  EXPECT_EQ(r[0], 0x3F80);
  EXPECT_EQ(r[1], 0x0000);
  EncodeFloat32(1.0f, WordOrder::kLowWordFirst, r);
  EXPECT_EQ(r[0], 0x0000);
  EXPECT_EQ(r[1], 0x3F80);
  EncodeFloat32(-2.5f, WordOrder::kHighWordFirst, r);  // 0xC0200000
  EXPECT_EQ(r[0], 0xC020);
  EXPECT_EQ(r[1], 0x0000);
  EncodeFloat32(2.1f, WordOrder::kHighWordFirst, r);  // 0x40066666
  EXPECT_EQ(r[0], 0x4006);
  EXPECT_EQ(r[1], 0x6666);
  EncodeFloat32(2.1f, WordOrder::kLowWordFirst, r);
  EXPECT_EQ(r[0], 0x6666);
  EXPECT_EQ(r[1], 0x4006);
  EncodeFloat32(2.1f, WordOrder::kHighWordFirstByteSwapped, r);
  EXPECT_EQ(r[0], 0x0640);
  EXPECT_EQ(r[1], 0x6666);
  EncodeFloat32(2.1f, WordOrder::kLowWordFirstByteSwapped, r);
  EXPECT_EQ(r[0], 0x6666);
  EXPECT_EQ(r[1], 0x0640);
}

TEST(Float32, AgreesWithLibmodbusInEveryOrder) {
  const float values[] = {0.0f, 1.0f, -1.0f, 2.1f, -0.5f, 11.0f, 1.5326e-3f, -1234.5f, 3.4e38f};
  for (float v : values) {
    std::uint16_t r[2];
    EncodeFloat32(v, WordOrder::kHighWordFirst, r);
    EXPECT_EQ(modbus_get_float_abcd(r), v);
    EncodeFloat32(v, WordOrder::kLowWordFirst, r);
    EXPECT_EQ(modbus_get_float_cdab(r), v);
    EncodeFloat32(v, WordOrder::kHighWordFirstByteSwapped, r);
    EXPECT_EQ(modbus_get_float_badc(r), v);
    EncodeFloat32(v, WordOrder::kLowWordFirstByteSwapped, r);
    EXPECT_EQ(modbus_get_float_dcba(r), v);
    for (WordOrder order :
         {WordOrder::kHighWordFirst, WordOrder::kLowWordFirst, WordOrder::kHighWordFirstByteSwapped,
          WordOrder::kLowWordFirstByteSwapped}) {
      EncodeFloat32(v, order, r);
      EXPECT_EQ(DecodeFloat32(r, order), v);
    }
  }
}

TEST(Float32, WordOrderLettersParse) {
  for (WordOrder order :
       {WordOrder::kHighWordFirst, WordOrder::kLowWordFirst, WordOrder::kHighWordFirstByteSwapped,
        WordOrder::kLowWordFirstByteSwapped}) {
    EXPECT_EQ(WordOrderFromLetters(WordOrderLetters(order)), order);
  }
  EXPECT_EQ(WordOrderLetters(WordOrder::kHighWordFirst), "abcd");
  EXPECT_EQ(WordOrderLetters(WordOrder::kLowWordFirstByteSwapped), "dcba");
  EXPECT_FALSE(WordOrderFromLetters("big").has_value());
}

TEST(Uint32, EveryWordOrder) {
  std::uint16_t r[2];
  EncodeUint32(86400u * 3u, WordOrder::kHighWordFirst, r);  // 259200 = 0x0003F480
  EXPECT_EQ(r[0], 0x0003);
  EXPECT_EQ(r[1], 0xF480);
  EXPECT_EQ(DecodeUint32(r, WordOrder::kHighWordFirst), 259200u);
  EncodeUint32(0x01020304u, WordOrder::kLowWordFirst, r);
  EXPECT_EQ(r[0], 0x0304);
  EXPECT_EQ(r[1], 0x0102);
  EncodeUint32(0x01020304u, WordOrder::kHighWordFirstByteSwapped, r);
  EXPECT_EQ(r[0], 0x0201);
  EXPECT_EQ(r[1], 0x0403);
  EncodeUint32(0x01020304u, WordOrder::kLowWordFirstByteSwapped, r);
  EXPECT_EQ(r[0], 0x0403);
  EXPECT_EQ(r[1], 0x0201);
  EXPECT_EQ(DecodeUint32(r, WordOrder::kLowWordFirstByteSwapped), 0x01020304u);
}

TEST(Int32AndInt16, TwosComplement) {
  std::uint16_t r[2];
  EncodeInt32(-2, WordOrder::kHighWordFirst, r);
  EXPECT_EQ(r[0], 0xFFFF);
  EXPECT_EQ(r[1], 0xFFFE);
  EXPECT_EQ(DecodeInt32(r, WordOrder::kHighWordFirst), -2);
  EncodeInt32(-2147483647 - 1, WordOrder::kLowWordFirst, r);
  EXPECT_EQ(r[0], 0x0000);
  EXPECT_EQ(r[1], 0x8000);
  EXPECT_EQ(DecodeInt32(r, WordOrder::kLowWordFirst), -2147483647 - 1);
  EXPECT_EQ(EncodeInt16(-500), 0xFE0C);
  EXPECT_EQ(DecodeInt16(0x8000), -32768);
  EXPECT_EQ(DecodeInt16(0x7FFF), 32767);
}

}  // namespace
}  // namespace canalid::core
