#pragma once
// Seeded synthetic data for the online-estimation tests (no dependence on <random> distributions).
#include <cstdint>
#include <vector>

#include "core/numerics/splitmix64.h"

namespace canalid::core::testdata {

/// SplitMix64 (core/numerics/splitmix64.h) with normal noise on top.
class TestRandom {
 public:
  explicit TestRandom(std::uint64_t seed) : random_(seed) {}
  double Uniform() { return random_.NextUniform(); }  // [0, 1)
  double Normal() {  // Irwin-Hall: unit variance, good enough for noise
    double s = -6.0;
    for (int i = 0; i < 12; ++i) s += Uniform();
    return s;
  }

 private:
  SplitMix64 random_;
};

/// PRBS-like two-level signal: a fresh random sign every `clock` samples.
inline std::vector<double> Prbs(int samples, int clock, std::uint64_t seed) {
  TestRandom rnd(seed);
  std::vector<double> out(static_cast<std::size_t>(samples));
  double level = 1.0;
  for (int k = 0; k < samples; ++k) {
    if (k % clock == 0) level = rnd.Uniform() < 0.5 ? -1.0 : 1.0;
    out[static_cast<std::size_t>(k)] = level;
  }
  return out;
}

struct PoolData {
  std::vector<double> q_in;
  std::vector<double> q_out;
  std::vector<double> level;   // measured (with noise)
  std::vector<double> b_true;  // per sample
  std::vector<int> nk_true;    // per sample
};

struct PoolSpec {
  int samples = 3000;
  double b = 60.0 / 6000.0;  // Ts / A with Ts = 60 s, A = 6000 m^2
  int nk = 7;
  double q0_m3s = 2.0;
  double q_in_amplitude_m3s = 0.2;
  double q_out_amplitude_m3s = 0.1;
  double offtake_m3s = 0.02;  // unmeasured constant: a drift in the level
  double noise_m = 0.002;
  int change_b_at = -1;  // from here on b = b_after
  double b_after = 0.0;
  int change_nk_at = -1;  // from here on nk = nk_after
  int nk_after = 0;
  int hold_from = -1;  // from here on (until hold_to) both flows are constant
  int hold_to = -1;
  std::uint64_t seed = 1;
};

/// The discrete ID model y(k) - y(k-1) = b (q_in(k - nk) - q_out(k - 1) - offtake) plus white
/// measurement noise on the level; PRBS-like inflow and outflow.
inline PoolData MakePool(const PoolSpec& s) {
  const auto n = static_cast<std::size_t>(s.samples);
  const std::vector<double> u_in = Prbs(s.samples, 8, s.seed);
  const std::vector<double> u_out = Prbs(s.samples, 13, s.seed + 1000);
  TestRandom noise(s.seed + 2000);
  PoolData d{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n),
             std::vector<double>(n), std::vector<int>(n)};
  for (std::size_t k = 0; k < n; ++k) {
    const bool hold = static_cast<int>(k) >= s.hold_from && static_cast<int>(k) < s.hold_to;
    d.q_in[k] = s.q0_m3s + (hold ? 0.0 : s.q_in_amplitude_m3s * u_in[k]);
    d.q_out[k] = s.q0_m3s - s.offtake_m3s + (hold ? 0.0 : s.q_out_amplitude_m3s * u_out[k]);
  }
  double y = 2.0;
  for (std::size_t k = 0; k < n; ++k) {
    const int ki = static_cast<int>(k);
    const double b = (s.change_b_at >= 0 && ki >= s.change_b_at) ? s.b_after : s.b;
    const int nk = (s.change_nk_at >= 0 && ki >= s.change_nk_at) ? s.nk_after : s.nk;
    d.b_true[k] = b;
    d.nk_true[k] = nk;
    if (ki >= 1 && ki >= nk) {
      y += b * (d.q_in[k - static_cast<std::size_t>(nk)] - d.q_out[k - 1] - s.offtake_m3s);
    }
    d.level[k] = y + s.noise_m * noise.Normal();
  }
  return d;
}

}  // namespace canalid::core::testdata
