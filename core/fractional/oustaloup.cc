#include "core/fractional/oustaloup.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {

int OustaloupSections(double low_rad_s, double high_rad_s, double sections_per_decade) {
  if (!(low_rad_s > 0.0 && high_rad_s > low_rad_s) || !std::isfinite(high_rad_s)) {
    throw std::invalid_argument("Oustaloup band [" + std::to_string(low_rad_s) + ", " +
                                std::to_string(high_rad_s) + "] rad/s must satisfy 0 < low < high");
  }
  if (!(sections_per_decade > 0.0 && sections_per_decade <= kMaxOustaloupSectionsPerDecade)) {
    throw std::invalid_argument(
        "Oustaloup sections_per_decade = " + std::to_string(sections_per_decade) +
        " is out of range (allowed: > 0 and <= 20)");
  }
  const double decades = std::log10(high_rad_s / low_rad_s);
  const double sections = std::max(1.0, std::ceil(sections_per_decade * decades));
  if (!(sections <= kMaxOustaloupSections)) {
    throw std::invalid_argument(
        "Oustaloup sections = " + std::to_string(sections) + " (" +
        std::to_string(sections_per_decade) + " per decade over " + std::to_string(decades) +
        " decades) is out of range (allowed: 1.." + std::to_string(kMaxOustaloupSections) + ")");
  }
  return static_cast<int>(sections);
}

OustaloupFilter OustaloupApproximation(double gamma, double low_rad_s, double high_rad_s,
                                       int sections) {
  if (!(gamma > -1.0 && gamma < 1.0)) {
    throw std::invalid_argument("OustaloupApproximation: gamma = " + std::to_string(gamma) +
                                " must be in (-1, 1)");
  }
  if (!(low_rad_s > 0.0 && high_rad_s > low_rad_s) || !std::isfinite(high_rad_s)) {
    throw std::invalid_argument("OustaloupApproximation: band [" + std::to_string(low_rad_s) +
                                ", " + std::to_string(high_rad_s) +
                                "] rad/s must satisfy 0 < low < high");
  }
  if (sections < 1 || sections > kMaxOustaloupSections) {
    throw std::invalid_argument("OustaloupApproximation: sections = " + std::to_string(sections) +
                                " is out of range (allowed: 1.." +
                                std::to_string(kMaxOustaloupSections) + ")");
  }
  OustaloupFilter filter;
  filter.gain = std::pow(high_rad_s, gamma);
  filter.zeros_rad_s.resize(sections);
  filter.poles_rad_s.resize(sections);
  const double ratio = high_rad_s / low_rad_s;
  for (int k = 1; k <= sections; ++k) {
    filter.zeros_rad_s(k - 1) = low_rad_s * std::pow(ratio, (k - 0.5 - 0.5 * gamma) / sections);
    filter.poles_rad_s(k - 1) = low_rad_s * std::pow(ratio, (k - 0.5 + 0.5 * gamma) / sections);
  }
  return filter;
}

OustaloupRealization RealizeOustaloup(const OustaloupFilter& filter) {
  const Eigen::Index n = filter.poles_rad_s.size();
  OustaloupRealization ss;
  ss.a = Eigen::MatrixXd::Zero(n, n);
  ss.b.resize(n);
  ss.c.resize(n);
  ss.d = filter.gain;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double p = filter.poles_rad_s(i);
    ss.c(i) = (filter.zeros_rad_s(i) - p) / p;
    ss.b(i) = p * filter.gain;
    ss.a(i, i) = -p;
    for (Eigen::Index j = 0; j < i; ++j) ss.a(i, j) = p * ss.c(j);
  }
  return ss;
}

}  // namespace canalid::core
