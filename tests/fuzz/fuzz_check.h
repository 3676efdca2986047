#pragma once
// Helpers shared by the fuzz targets (tests/fuzz/*_fuzz.cc): a property check that aborts (a
// finding for libFuzzer and for the replay driver alike) and the bytes as text.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace canalid::fuzz {

/// Aborts with `what` when `condition` is false: a broken property of the code under test.
inline void Check(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "fuzz property violated: %s\n", what);
    std::abort();
  }
}

inline std::string_view Text(const uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace canalid::fuzz
