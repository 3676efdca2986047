#pragma once
// Commensurate fractional state-space models (core/fractional/commensurate_state_space.h) the
// tests identify: the LPV paper's published ones and an integer second-order one.
#include "core/fractional/commensurate_state_space.h"

namespace canalid::core::testdata {

/// The LPV paper, Table 3, pool P1, OP1: alpha = 0.5 (b1..b7), nk = 17.
inline CommensurateModel SeedOneHalf() {
  CommensurateModel m;
  m.q = 2;
  m.a.resize(4);
  m.a << -0.1313, 0.0370, 0.0019, 0.0995e-3;
  m.c.resize(3);
  m.c << 55.082, -345.72, 633.48;
  m.delay_samples = 17;
  return m;
}

/// The same pool and operating point at alpha = 0.25 (c1..c15), nk = 17.
inline CommensurateModel SeedOneQuarter() {
  CommensurateModel m;
  m.q = 4;
  m.a.resize(8);
  m.a << -2.1318, 2.0729, -1.1719, 0.4176, -0.0948, 0.0133, -0.0010, 0.0464e-3;
  m.c.resize(7);
  m.c << -3.1753, 2.1646, 2.2736, 0.3424, -1.3216, -2.0112, -1.9148;
  m.delay_samples = 17;
  return m;
}

/// q = 1: x[k+1] = (I + A) x[k] + B u, poles of z^2 - 1.5 z + 0.6 (inside the unit circle).
inline CommensurateModel IntegerSecondOrder() {
  CommensurateModel m;
  m.q = 1;
  m.a.resize(2);
  m.a << 0.5, 0.1;
  m.c.resize(1);
  m.c << 0.5;
  m.delay_samples = 3;
  return m;
}

}  // namespace canalid::core::testdata
