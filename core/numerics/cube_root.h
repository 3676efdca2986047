#pragma once
#include <bit>
#include <cmath>
#include <cstdint>

namespace canalid::core {

/// The real cube root of x, within 4 units in the last place of glibc's cbrt (itself within one
/// of the exact root) for positive x between 2^-1000 and 2^1000; every other x (zero, negative,
/// tiny, huge, infinite, NaN) goes to std::cbrt.  About twice as fast as glibc's cbrt and inlined:
/// a seed from the exponent bits divided by three (within 4 %), two Halley steps (cubic
/// convergence) and one Newton step on the residual.  For the Manning friction of the simulator's
/// every node and Newton iteration, where libm's cbrt took a sixth of a step.
inline double CubeRoot(double x) {
  if (!(x >= 0x1p-1000 && x <= 0x1p1000)) return std::cbrt(x);
  // Dividing the bit pattern by three divides the exponent by three; the constant restores the
  // bias (Kahan's seed for the cube root).
  constexpr std::uint64_t kSeedBias = 0x2A9F7893782DA1CEull;
  double y = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) / 3 + kSeedBias);
  for (int k = 0; k < 2; ++k) {
    const double y3 = y * y * y;
    y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
  }
  return y - (y * y * y - x) / (3.0 * y * y);
}

}  // namespace canalid::core
