#pragma once
#include <cstdio>
#include <cstdlib>

/// Invariant check that is never compiled out: prints the condition and location, then aborts.
/// For broken invariants only; bad input is reported with exceptions (start-up) or typed results.
#define CANALID_DEMAND(condition, message)                                                       \
  do {                                                                                           \
    if (!(condition)) {                                                                          \
      std::fprintf(stderr, "%s:%d: invariant failed: %s (%s)\n", __FILE__, __LINE__, #condition, \
                   message);                                                                     \
      std::abort();                                                                              \
    }                                                                                            \
  } while (false)
