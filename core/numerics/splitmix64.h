#pragma once
#include <cstdint>

namespace canalid::core {

/// SplitMix64 (Steele, Lea and Flood 2014; Vigna's splitmix64.c): a 64-bit counter advanced by
/// the golden-ratio increment 0x9E3779B97F4A7C15 and a bijective finaliser
///   z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9;  z = (z ^ (z >> 27)) * 0x94D049BB133111EB;
///   z ^ (z >> 31).
/// The seeded generator of tests and of the simulator's noise streams: the same numbers on every
/// platform and standard library.  Pure, no allocation.
class SplitMix64 final {
 public:
  explicit constexpr SplitMix64(std::uint64_t seed) : state_(seed) {}
  /// The next 64-bit output.
  constexpr std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// A double uniform in [0, 1): the top 53 bits of Next() times 2^-53.
  constexpr double NextUniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

/// The first output of SplitMix64 seeded with x: a well-mixed 64-bit hash of x (e.g. independent
/// seeds from (seed, index) pairs).
constexpr std::uint64_t SplitMix64Hash(std::uint64_t x) { return SplitMix64(x).Next(); }

}  // namespace canalid::core
