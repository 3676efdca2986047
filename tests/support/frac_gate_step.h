#pragma once
// Gate-step records through the fractional first-order model with delay
// K e^{-tau s}/(1 + T s^alpha), made from its exact step response (the Mittag-Leffler function of
// core/fractional/mittag_leffler.h, independent of the Oustaloup simulator that the fits and
// `canalid simulate` use), for the suites that identify, simulate and report on such records.
#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "core/fractional/mittag_leffler.h"

namespace canalid::testing {

/// The unit-step response of 1/(1 + T s^alpha) `since_s` after the step reached it:
/// 1 - E_alpha(-since^alpha / T), and 0 before (since_s <= 0).
inline double FracUnitStep(double alpha, double time_constant_s, double since_s) {
  return since_s > 0.0
             ? 1.0 - core::MittagLeffler(alpha, -std::pow(since_s, alpha) / time_constant_s)
             : 0.0;
}

/// The model and the gate step it is driven by.
struct FracGateStep {
  double gain;             // K, mm of level per mm of gate
  double time_constant_s;  // T [s^alpha]
  double delay_s;
  double alpha;
  double gate_from_mm;
  double gate_to_mm;
};

/// The record's sampling, its seeded white level noise and its column names.
struct FracStepRecord {
  int samples;
  int step_sample;  // the first sample at gate_to_mm
  double ts_s;
  double noise_mm;
  unsigned seed;
  std::string input = "gate";
  std::string output = "level";
};

/// CSV "time_s,INPUT,OUTPUT": the gate held at gate_from_mm, then gate_to_mm; the level rests at
/// 60 mm and follows the exact step response, plus the noise.
inline std::string FracGateStepCsv(const FracGateStep& e, const FracStepRecord& r) {
  std::mt19937 rng(r.seed);
  std::normal_distribution<double> noise(0.0, r.noise_mm);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s," << r.input << "," << r.output << "\n";
  for (int k = 0; k < r.samples; ++k) {
    const double response =
        FracUnitStep(e.alpha, e.time_constant_s, (k - r.step_sample) * r.ts_s - e.delay_s);
    csv << k * r.ts_s << "," << (k < r.step_sample ? e.gate_from_mm : e.gate_to_mm) << ","
        << 60.0 + e.gain * (e.gate_to_mm - e.gate_from_mm) * response + noise(rng) << "\n";
  }
  return csv.str();
}

}  // namespace canalid::testing
