#include "sim/prbs_sequence.h"

#include <stdexcept>
#include <string>

namespace canalid::sim {

std::vector<int> PrbsSequence(int order, std::uint64_t seed) {
  // Galois toggle masks of primitive polynomials of degree n (maximal-length LFSRs).
  static constexpr unsigned kTaps[17] = {0,     0,      0x3,    0x6,    0xC,   0x14,
                                         0x30,  0x60,   0xB8,   0x110,  0x240, 0x500,
                                         0xE08, 0x1C80, 0x3802, 0x6000, 0xD008};
  if (order < 2 || order > 16) {
    throw std::invalid_argument("PrbsSequence: order " + std::to_string(order) +
                                " must be in [2, 16]");
  }
  const unsigned mask = (1u << order) - 1u;
  unsigned state = static_cast<unsigned>(seed % mask) + 1u;  // never zero
  const unsigned period = mask;
  std::vector<int> out(period);
  for (unsigned k = 0; k < period; ++k) {
    out[k] = (state & 1u) != 0u ? 1 : -1;
    // Galois form: shift right and toggle the tap bits when a one falls out.
    const unsigned lsb = state & 1u;
    state >>= 1;
    if (lsb != 0u) state ^= kTaps[order];
  }
  return out;
}

}  // namespace canalid::sim
