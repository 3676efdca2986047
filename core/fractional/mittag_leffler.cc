#include "core/fractional/mittag_leffler.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace canalid::core {
namespace {

constexpr double kSeriesLimit = 15.0;  // largest t = (-z)^(1/alpha) handled by the series

double Series(double alpha, double z, double t) {
  // Terms from exp/lgamma so that Gamma(alpha k + 1) never overflows; long double absorbs the
  // alternating-series cancellation.
  const long double log_abs_z = std::log(static_cast<long double>(-z));
  long double sum = 1.0L;
  long double largest = 1.0L;
  for (int k = 1; k < 100000; ++k) {
    const long double log_term =
        k * log_abs_z - std::lgamma(static_cast<long double>(alpha) * k + 1);
    const long double magnitude = std::exp(log_term);
    sum += (k % 2 == 0) ? magnitude : -magnitude;
    largest = std::max(largest, magnitude);
    // Past the peak the terms decrease monotonically; stop once they are far below precision.
    if (magnitude < 1e-22L * largest && alpha * k > t + 2.0) break;
  }
  return static_cast<double>(sum);
}

double LaplaceInversion(double alpha, double t) {
  // With r = s / t the factor e^{-s} puts the bulk of the mass at s ~ 1 (v ~ 0) whatever t is;
  // s = exp((pi/2) sinh v) then decays double-exponentially on both sides.  K_alpha peaks at
  // r = 1, i.e. s = t, with a width of about pi |1 - alpha| / alpha in log s: the step in v is
  // chosen to resolve that peak where it sits (its weight is only ~e^{-t} but the accuracy goal
  // is absolute).
  const double half_pi = 0.5 * std::numbers::pi;
  const double v_peak = std::asinh(std::log(t) / half_pi);
  const double peak_width =
      std::numbers::pi * std::abs(1.0 - alpha) / alpha / (half_pi * std::cosh(v_peak));
  // The peak carries a weight of about e^{-t}: beyond t = 30 even an unresolved peak stays
  // below 1e-12, so the fine step is only paid for 15 < t <= 30.
  const double step = t > 30.0 ? 0.02 : std::max(2e-4, std::min(0.02, peak_width / 4.0));
  const double cos_a = std::cos(alpha * std::numbers::pi);
  const double sin_a = std::sin(alpha * std::numbers::pi);
  const double log_t = std::log(t);
  // e^{-s} K_alpha(r) r (ds/dv) / s with r = s/t; K_alpha(r) r = sin(a pi) r^a / (pi ((r^a +
  // cos(a pi))^2 + sin(a pi)^2)), the denominator written so that it stays positive.
  auto integrand = [&](double v) {
    const double ev = std::exp(v);
    const double x = half_pi * 0.5 * (ev - 1.0 / ev);
    if (x > 700.0 || x < -700.0) return 0.0;
    const double s = std::exp(x);
    const double ra = std::exp(alpha * (x - log_t));
    const double kernel_r =
        sin_a * ra / (std::numbers::pi * ((ra + cos_a) * (ra + cos_a) + sin_a * sin_a));
    return std::exp(-s) * kernel_r * half_pi * 0.5 * (ev + 1.0 / ev);
  };
  // Below s = e^{-x_low} the integrand (s/t)^alpha ... is under 1e-19; above v = 3.5
  // (s = e^{26}) e^{-s} underflows.
  const double x_low = (45.0 + alpha * std::log(t)) / alpha;
  const double v_low = -std::asinh(x_low / half_pi);
  const int lo = static_cast<int>(std::floor(v_low / step));
  const int hi = static_cast<int>(std::ceil(3.5 / step));
  double sum = 0.0;
  for (int i = lo; i <= hi; ++i) sum += integrand(i * step);
  double value = sum * step;
  if (alpha > 1.0) {
    const double angle = std::numbers::pi / alpha;
    value += 2.0 / alpha * std::exp(t * std::cos(angle)) * std::cos(t * std::sin(angle));
  }
  return value;
}

}  // namespace

double MittagLeffler(double alpha, double z) {
  if (!(alpha > 0.0 && alpha < 2.0)) {
    throw std::invalid_argument("MittagLeffler: alpha = " + std::to_string(alpha) +
                                " must be in (0, 2)");
  }
  if (!(z <= 0.0) || !std::isfinite(z)) {
    throw std::invalid_argument("MittagLeffler: z = " + std::to_string(z) +
                                " must be finite and <= 0");
  }
  if (z == 0.0) return 1.0;
  if (alpha == 1.0) return std::exp(z);
  const double t = std::pow(-z, 1.0 / alpha);
  if (t <= kSeriesLimit) return Series(alpha, z, t);
  return LaplaceInversion(alpha, t);
}

}  // namespace canalid::core
