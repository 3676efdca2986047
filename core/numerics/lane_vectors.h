#pragma once
#include <cstdint>

namespace canalid::core {

/// W lanes of doubles as one value (GCC's and Clang's vector extension): +, -, *, / act lane by
/// lane with IEEE rounding, as on doubles (without FMA, which the build never contracts to); a
/// comparison gives a mask of -1 / 0 per lane.  Spelled out per width: GCC drops a vector_size
/// whose value depends on a template parameter.
template <int W>
struct LaneVectors;
template <>
struct LaneVectors<2> {  // one SSE2 register
  using Lanes = double __attribute__((vector_size(2 * sizeof(double))));
  using Mask = std::int64_t __attribute__((vector_size(2 * sizeof(std::int64_t))));
};
template <>
struct LaneVectors<4> {  // one AVX2 register
  using Lanes = double __attribute__((vector_size(4 * sizeof(double))));
  using Mask = std::int64_t __attribute__((vector_size(4 * sizeof(std::int64_t))));
};

/// Two doubles in one SSE2 register, the baseline x86-64 ISA: for the short runs over a bank's
/// candidates (tens), where a loop's bookkeeping costs as much as its work.
using DoublePair = LaneVectors<2>::Lanes;

/// The two doubles at `at`, any alignment.
inline DoublePair LoadPair(const double* at) {
  DoublePair v;
  __builtin_memcpy(&v, at, sizeof(v));
  return v;
}

/// Writes `v` to the two doubles at `at`, any alignment.
inline void StorePair(double* at, DoublePair v) { __builtin_memcpy(at, &v, sizeof(v)); }

}  // namespace canalid::core
