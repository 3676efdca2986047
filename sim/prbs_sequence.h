#pragma once
#include <cstdint>
#include <vector>

namespace canalid::sim {

/// Maximal-length pseudo-random binary sequence from a Galois linear feedback shift register
/// of order n (2 <= n <= 16) with a primitive feedback polynomial: period 2^n - 1, with 2^(n-1)
/// values +1 and 2^(n-1) - 1 values -1 per period.  `seed` picks the starting state (any value;
/// it is reduced to a non-zero n-bit state).
/// @throws std::invalid_argument if order is outside [2, 16].
std::vector<int> PrbsSequence(int order, std::uint64_t seed);

}  // namespace canalid::sim
