#include "core/experiment/setpoint_limiter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalid::core {
namespace {

constexpr SetpointLimits kGate{0.0, 1.5, 0.01};  // gate opening 0..1.5 m, 1 cm/s

TEST(SetpointLimiter, ClampsToRangeThenToRate) {
  // From 0.50 m, 10 s later at most 0.10 m of travel.
  LimitedSetpoint r = LimitSetpoint(kGate, 0.55, 0.50, 10.0);
  EXPECT_DOUBLE_EQ(r.value, 0.55);
  EXPECT_FALSE(r.clamped);
  EXPECT_FALSE(r.rate_limited);
  r = LimitSetpoint(kGate, 0.90, 0.50, 10.0);
  EXPECT_DOUBLE_EQ(r.value, 0.60);
  EXPECT_TRUE(r.rate_limited);
  r = LimitSetpoint(kGate, -3.0, 0.05, 10.0);
  EXPECT_DOUBLE_EQ(r.value, 0.0);
  EXPECT_TRUE(r.clamped);
  EXPECT_FALSE(r.rate_limited);
  r = LimitSetpoint(kGate, 2.0, 1.45, 100.0);
  EXPECT_DOUBLE_EQ(r.value, 1.5);
  EXPECT_TRUE(r.clamped);
  // Time going backwards allows no movement.
  r = LimitSetpoint(kGate, 1.0, 0.5, -4.0);
  EXPECT_DOUBLE_EQ(r.value, 0.5);
  EXPECT_EQ(LimitSetpoint(kGate, std::nan(""), 0.5, 1.0).status, SetpointStatus::kNotFinite);
}

TEST(SetpointLimiter, RateWinsWhenThePreviousValueIsOutOfRange) {
  // The plant sits at 2.0 m (above the 1.5 m bound): move down by at most 0.01 m in 1 s.
  const LimitedSetpoint r = LimitSetpoint(kGate, 1.0, 2.0, 1.0);
  EXPECT_DOUBLE_EQ(r.value, 1.99);
  EXPECT_TRUE(r.clamped == false && r.rate_limited);
}

TEST(SetpointLimiter, InfiniteRateDisablesRateLimiting) {
  const SetpointLimits free{0.0, 1.5, std::numeric_limits<double>::infinity()};
  const LimitedSetpoint r = LimitSetpoint(free, 1.2, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(r.value, 1.2);
  EXPECT_FALSE(r.rate_limited);
}

TEST(SetpointLimiter, NeedsAReferenceAndDoesNotMoveItByItself) {
  SetpointLimiter limiter(kGate);
  EXPECT_EQ(limiter.Apply(1.0, 0.0).status, SetpointStatus::kNoReference);
  limiter.Reset(0.3, 100.0);
  const LimitedSetpoint first = limiter.Apply(1.0, 105.0);
  EXPECT_DOUBLE_EQ(first.value, 0.35);
  // Apply is const: a second request at the same time is limited from the same reference.
  EXPECT_DOUBLE_EQ(limiter.Apply(1.0, 105.0).value, 0.35);
  limiter.Reset(first.value, 105.0);
  EXPECT_DOUBLE_EQ(limiter.Apply(1.0, 106.0).value, 0.36);
  limiter.Forget();
  EXPECT_FALSE(limiter.has_reference());
  EXPECT_EQ(limiter.Apply(1.0, 107.0).status, SetpointStatus::kNoReference);
}

TEST(SetpointLimiter, RejectsBadLimits) {
  EXPECT_THROW(SetpointLimiter({1.0, 0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(SetpointLimiter({0.0, 1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(SetpointLimiter({0.0, std::nan(""), 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
