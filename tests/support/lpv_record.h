#pragma once
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace canalid::testing {

/// The LPV plant of the CLI and plant tests: y[k] = -a1(theta) y[k-1] + b1(theta) u[k-nk], a1 and
/// b1 quadratic in theta (highest degree first), nk = 3 samples.
inline constexpr double kLpvA1[3] = {0.05, -0.2, -0.7};
inline constexpr double kLpvB1[3] = {-0.02, 0.1, 0.05};
inline constexpr int kLpvNkSamples = 3;
inline constexpr int kLpvPerBand = 600;
/// One operating point per band: theta is a staircase through them, kLpvPerBand samples each.
inline const std::vector<double> kLpvThetas = {1.1, 1.3, 1.5, 1.7, 1.9};

/// p[0] theta^2 + p[1] theta + p[2].
inline double Quadratic(const double (&p)[3], double theta) {
  return (p[0] * theta + p[1]) * theta + p[2];
}

/// The plant's record as CSV (time_s,gate,level,upstream; 10 s sampling; upstream = theta): u a
/// random +-1 sequence held 5 samples, at rest (u = 0) for the first 10 samples, and the level
/// y[k] + noise_gain * N(0, noise_std) from std::mt19937(seed).
inline std::string LpvCsv(unsigned seed, double noise_std, double noise_gain = 1.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_std);
  const auto per_band = static_cast<std::size_t>(kLpvPerBand);
  const auto nk = static_cast<std::size_t>(kLpvNkSamples);
  const std::size_t n = per_band * kLpvThetas.size();
  std::vector<double> u(n, 0.0), y(n, 0.0);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,gate,level,upstream\n";
  for (std::size_t k = 0; k < n; ++k) {
    const double theta = kLpvThetas[k / per_band];
    if (k >= 10) u[k] = k % 5 == 0 ? ((rng() & 1U) ? 1.0 : -1.0) : u[k - 1];
    if (k >= 1) {
      y[k] = -Quadratic(kLpvA1, theta) * y[k - 1] +
             Quadratic(kLpvB1, theta) * (k >= nk ? u[k - nk] : 0.0);
    }
    csv << static_cast<double>(k) * 10.0 << "," << u[k] << "," << y[k] + noise_gain * noise(rng)
        << "," << theta << "\n";
  }
  return csv.str();
}

}  // namespace canalid::testing
