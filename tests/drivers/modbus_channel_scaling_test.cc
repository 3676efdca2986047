#include "drivers/modbus/channel_scaling.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace canalid::drivers {
namespace {

ChannelScaling Scaling(RegisterType type, WordOrder order, double scale = 1.0,
                       double offset = 0.0) {
  ChannelScaling s;
  s.type = type;
  s.word_order = order;
  s.scale = scale;
  s.offset = offset;
  return s;
}

// Register images written by hand from the Modbus convention (big-endian words, ABCD vs CDAB).
TEST(ChannelScaling, DecodesKnownRegisterImages) {
  using enum RegisterType;
  using enum WordOrder;
  const std::array<uint16_t, 1> neg_one16 = {0xFFFF};
  EXPECT_EQ(DecodeChannel(Scaling(kU16, kHighWordFirst), neg_one16).value, 65535.0);
  EXPECT_EQ(DecodeChannel(Scaling(kI16, kHighWordFirst), neg_one16).value, -1.0);
  const std::array<uint16_t, 1> min16 = {0x8000};
  EXPECT_EQ(DecodeChannel(Scaling(kI16, kHighWordFirst), min16).value, -32768.0);

  const std::array<uint16_t, 2> abcd = {0x1234, 0x5678};
  EXPECT_EQ(DecodeChannel(Scaling(kU32, kHighWordFirst), abcd).value, 305419896.0);  // 0x12345678
  EXPECT_EQ(DecodeChannel(Scaling(kU32, kLowWordFirst), abcd).value, 1450709556.0);  // 0x56781234
  const std::array<uint16_t, 2> minus_two = {0xFFFF, 0xFFFE};
  EXPECT_EQ(DecodeChannel(Scaling(kI32, kHighWordFirst), minus_two).value, -2.0);
  EXPECT_EQ(DecodeChannel(Scaling(kI32, kLowWordFirst), minus_two).value, -65537.0);  // 0xFFFEFFFF
  const std::array<uint16_t, 2> min32 = {0x8000, 0x0000};
  EXPECT_EQ(DecodeChannel(Scaling(kI32, kHighWordFirst), min32).value, -2147483648.0);

  // IEEE 754 binary32: 1.0 = 0x3F800000, -2.5 = 0xC0200000, 0.1f = 0x3DCCCCCD.
  const std::array<uint16_t, 2> one = {0x3F80, 0x0000};
  EXPECT_EQ(DecodeChannel(Scaling(kF32, kHighWordFirst), one).value, 1.0);
  const std::array<uint16_t, 2> minus_2_5_swapped = {0x0000, 0xC020};
  EXPECT_EQ(DecodeChannel(Scaling(kF32, kLowWordFirst), minus_2_5_swapped).value, -2.5);
  const std::array<uint16_t, 2> tenth = {0x3DCC, 0xCCCD};
  EXPECT_EQ(DecodeChannel(Scaling(kF32, kHighWordFirst), tenth).value, static_cast<double>(0.1f));
}

TEST(ChannelScaling, EncodesKnownRegisterImages) {
  using enum RegisterType;
  using enum WordOrder;
  std::array<uint16_t, 1> one_reg{};
  ASSERT_EQ(EncodeChannel(Scaling(kI16, kHighWordFirst), -1.0, one_reg), ScalingError::kNone);
  EXPECT_EQ(one_reg[0], 0xFFFF);
  std::array<uint16_t, 2> two{};
  ASSERT_EQ(EncodeChannel(Scaling(kF32, kLowWordFirst), -2.5, two), ScalingError::kNone);
  EXPECT_EQ(two[0], 0x0000);
  EXPECT_EQ(two[1], 0xC020);
  ASSERT_EQ(EncodeChannel(Scaling(kI32, kHighWordFirst), -2147483648.0, two), ScalingError::kNone);
  EXPECT_EQ(two[0], 0x8000);
  EXPECT_EQ(two[1], 0x0000);
  ASSERT_EQ(EncodeChannel(Scaling(kU32, kLowWordFirst), 305419896.0, two), ScalingError::kNone);
  EXPECT_EQ(two[0], 0x5678);
  EXPECT_EQ(two[1], 0x1234);
}

// Scale 0.001 m per count and offset 100 m: a level of 101.234 m is raw 1234 (exactly, after
// rounding). Every type and word order must return the engineering value to within half a count
// (integers) or float precision relative to the raw value (f32).
TEST(ChannelScaling, RoundTripsEveryTypeAndWordOrder) {
  std::mt19937 rng(42);
  for (auto type : {RegisterType::kU16, RegisterType::kI16, RegisterType::kU32, RegisterType::kI32,
                    RegisterType::kF32}) {
    for (auto order : {WordOrder::kHighWordFirst, WordOrder::kLowWordFirst}) {
      const ChannelScaling s = Scaling(type, order, 0.001, 100.0);
      double raw_low = 0.0;
      double raw_high = 65535.0;
      if (type == RegisterType::kI16) raw_low = -32768.0, raw_high = 32767.0;
      if (type == RegisterType::kU32) raw_high = 4294967295.0;
      if (type == RegisterType::kI32) raw_low = -2147483648.0, raw_high = 2147483647.0;
      if (type == RegisterType::kF32) raw_low = -1e6, raw_high = 1e6;
      std::vector<double> raws = {raw_low, raw_high, 0.0, 1234.0};
      std::uniform_real_distribution<double> uniform(raw_low, raw_high);
      for (int i = 0; i < 200; ++i) raws.push_back(std::round(uniform(rng)));
      for (double raw : raws) {
        const double value = raw * 0.001 + 100.0;
        std::vector<uint16_t> regs(static_cast<std::size_t>(RegisterCount(type)));
        ASSERT_EQ(EncodeChannel(s, value, regs), ScalingError::kNone) << raw;
        EXPECT_EQ(RawFromRegisters(type, order, regs),
                  type == RegisterType::kF32 ? static_cast<float>(raw) : raw);
        const DecodedValue back = DecodeChannel(s, regs);
        ASSERT_TRUE(back.ok());
        // f32: 24-bit mantissa, |raw| <= 1e6 < 2^24, so integers are exact; integer types are
        // exact by construction. The only error is the double arithmetic of scale and offset.
        EXPECT_NEAR(back.value, value, 1e-9 * std::max(1.0, std::abs(value))) << raw;
      }
    }
  }
}

TEST(ChannelScaling, RangeAndRepresentabilityAreTypedErrors) {
  ChannelScaling s = Scaling(RegisterType::kU16, WordOrder::kHighWordFirst, 0.01, 0.0);
  s.min_value = 0.0;
  s.max_value = 600.0;
  std::array<uint16_t, 1> reg = {0xFFFF};  // 655.35 > 600
  const DecodedValue d = DecodeChannel(s, reg);
  EXPECT_EQ(d.error, ScalingError::kOutOfRange);
  EXPECT_DOUBLE_EQ(d.value, 655.35);
  reg[0] = 7;
  EXPECT_EQ(EncodeChannel(s, 600.01, reg), ScalingError::kOutOfRange);
  EXPECT_EQ(reg[0], 7) << "untouched on error";
  EXPECT_EQ(EncodeChannel(s, std::nan(""), reg), ScalingError::kNotFinite);

  ChannelScaling wide = Scaling(RegisterType::kI16, WordOrder::kHighWordFirst);
  EXPECT_EQ(EncodeChannel(wide, 32767.4, reg), ScalingError::kNone);
  EXPECT_EQ(EncodeChannel(wide, 32767.5, reg), ScalingError::kNotRepresentable);
  EXPECT_EQ(EncodeChannel(wide, -32768.5, reg), ScalingError::kNotRepresentable);
  wide.type = RegisterType::kF32;
  std::array<uint16_t, 2> two{};
  EXPECT_EQ(EncodeChannel(wide, 1e39, two), ScalingError::kNotRepresentable);  // > FLT_MAX
  EXPECT_EQ(EncodeChannel(wide, 1.0, reg), ScalingError::kWrongRegisterCount);
  EXPECT_EQ(DecodeChannel(wide, reg).error, ScalingError::kWrongRegisterCount);

  const std::array<uint16_t, 2> nan_bits = {0x7FC0, 0x0000};
  const std::array<uint16_t, 2> inf_bits = {0x7F80, 0x0000};
  EXPECT_EQ(DecodeChannel(wide, nan_bits).error, ScalingError::kNotFinite);
  EXPECT_EQ(DecodeChannel(wide, inf_bits).error, ScalingError::kNotFinite);
}

TEST(ChannelScaling, ValidationNamesTheField) {
  ChannelScaling s;
  s.scale = 0.0;
  EXPECT_THROW(ValidateChannelScaling(s), std::invalid_argument);
  s.scale = 1.0;
  s.min_value = 2.0;
  s.max_value = 1.0;
  try {
    ValidateChannelScaling(s);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_value"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(ValidateChannelScaling(ChannelScaling{}));
}

}  // namespace
}  // namespace canalid::drivers
