#pragma once
#include "sim/canal.h"

namespace canalid::testing {

/// ASCE test canal 2, pool 2: 3000 m long, 7 m bottom width, side slope 1.5, bed slope 1e-4,
/// Manning n 0.02, 2.1 m target depth.
inline sim::Pool Canal2Pool2() {
  sim::Pool p;
  p.name = "2";
  p.length_m = 3000;
  p.bottom_width_m = 7;
  p.side_slope = 1.5;
  p.bed_slope = 1e-4;
  p.manning_n = 0.02;
  p.target_depth_m = 2.1;
  return p;
}

}  // namespace canalid::testing
