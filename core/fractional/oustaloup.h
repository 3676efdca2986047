#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Oustaloup's recursive approximation of s^gamma, -1 < gamma < 1, over [low, high] rad/s with
/// N = sections first-order sections:
///   s^gamma ~ gain prod_{k=1..N} (s + zero_k) / (s + pole_k),
///   zero_k = low (high/low)^{(k - 1/2 - gamma/2) / N},  pole_k = low (high/low)^{(k - 1/2 +
///   gamma/2) / N},  gain = high^gamma,
/// so that |H| = low^gamma at DC, high^gamma at infinity and the phase is ~ gamma pi / 2 inside
/// the band (ripple shrinking with sections per decade).
struct OustaloupFilter {
  double gain = 1.0;
  Eigen::VectorXd zeros_rad_s;
  Eigen::VectorXd poles_rad_s;
};

/// Bounds on the approximation's density and size: the realisation has one state per section and
/// is simulated with a dense matrix (cost N^2 per sample, N^3 to discretise), so beyond these
/// the program would run for hours; the default band needs 2-3 per decade and about 25 in all.
inline constexpr double kMaxOustaloupSectionsPerDecade = 20.0;
inline constexpr int kMaxOustaloupSections = 200;

/// The number of sections for a band at a density: ceil(sections_per_decade * log10(high/low)),
/// at least 1.
/// @throws std::invalid_argument naming the value unless 0 < low < high (finite), 0 <
///         sections_per_decade <= kMaxOustaloupSectionsPerDecade and the count is at most
///         kMaxOustaloupSections.
int OustaloupSections(double low_rad_s, double high_rad_s, double sections_per_decade);

/// @throws std::invalid_argument unless -1 < gamma < 1, 0 < low < high and
///         1 <= sections <= kMaxOustaloupSections.
OustaloupFilter OustaloupApproximation(double gamma, double low_rad_s, double high_rad_s,
                                       int sections);

/// Continuous single-input single-output state space x' = A x + B u, y = C x + D u.
struct OustaloupRealization {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
};

/// The filter as a cascade of first-order sections with scaled states xi_k (xi_k' = -p_k xi_k +
/// p_k v_k, section output v_k + ((z_k - p_k)/p_k) xi_k): lower triangular A, well conditioned
/// even over many decades.
OustaloupRealization RealizeOustaloup(const OustaloupFilter& filter);

}  // namespace canalid::core
