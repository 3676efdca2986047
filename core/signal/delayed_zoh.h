#pragma once
#include <Eigen/Core>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/signal/fractional_delay.h"

namespace canalid::core {

/// Exact zero-order-hold discretisation of a SISO state-space model with an input delay that
/// need not be a whole number of samples:
///   x'(t) = A x(t) + B u(t - tau),  y = C x,   tau = (d + f) Ts,  d integer, 0 <= f < 1.
/// With a piecewise-constant input u(t) = u_k on [k Ts, (k+1) Ts), the delayed input over one
/// sample is u_{k-d-1} for the first f Ts and u_{k-d} for the rest, so
///   x_{k+1} = Phi(Ts) x_k + Phi((1-f) Ts) Gamma(f Ts) u_{k-d-1} + Gamma((1-f) Ts) u_{k-d},
/// where Phi(h) = e^{A h} and Gamma(h) = int_0^h e^{A s} ds B (from one matrix exponential of
/// the augmented matrix [[A, B], [0, 0]] h).  Exact for inputs held over each sample.
/// Inputs before the record are taken as 0 (the system starts at rest in deviation variables).
template <int N>
class DelayedZoh final {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  using RowVector = Eigen::Matrix<double, 1, N>;

  /// @throws std::invalid_argument if sample_time_s <= 0 or delay_s < 0 (or not finite), or if
  ///         delay_s / sample_time_s exceeds kMaxDelaySamples (1e7 samples: the whole count is an
  ///         int, and SoptdPlant keeps a ring of that many inputs).
  DelayedZoh(const Matrix& a, const Vector& b, const RowVector& c, double sample_time_s,
             double delay_s)
      : c_(c) {
    if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
      throw std::invalid_argument("DelayedZoh: sample_time_s must be > 0");
    }
    if (!(delay_s >= 0.0) || !std::isfinite(delay_s)) {
      throw std::invalid_argument("DelayedZoh: delay_s must be >= 0");
    }
    const double samples = delay_s / sample_time_s;
    if (!(samples <= kMaxDelaySamples)) {
      throw std::invalid_argument(
          "DelayedZoh: delay_s / sample_time_s = " + std::to_string(delay_s) + " s / " +
          std::to_string(sample_time_s) + " s = " + std::to_string(samples) +
          " samples must be in [0, 1e7]");
    }
    whole_delay_ = static_cast<int>(std::floor(samples));
    const double fraction = samples - whole_delay_;
    Matrix phi_rest;
    Vector gamma_rest;
    Vector gamma_first;
    Discretise(a, b, sample_time_s, phi_, gamma_rest);  // gamma_rest reused below
    Discretise(a, b, (1.0 - fraction) * sample_time_s, phi_rest, gamma_rest);
    Matrix unused;
    Discretise(a, b, fraction * sample_time_s, unused, gamma_first);
    gamma_late_ = gamma_rest;               // multiplies u_{k-d}
    gamma_early_ = phi_rest * gamma_first;  // multiplies u_{k-d-1}
  }

  int whole_delay() const { return whole_delay_; }

  /// One step for streaming use (what Simulate does per sample): x_{k+1} from x_k and the held
  /// inputs u_{k-d-1} (early) and u_{k-d} (late); y_k = Output(x_k).
  Vector Next(const Vector& x, double u_early, double u_late) const {
    return phi_ * x + gamma_early_ * u_early + gamma_late_ * u_late;
  }
  double Output(const Vector& x) const { return c_ * x; }

  /// Simulates from rest: y_k for k = 0..n-1 given u_k (deviation values).
  void Simulate(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> y) const {
    const Eigen::Index n = u.size();
    Vector x = Vector::Zero();
    for (Eigen::Index k = 0; k < n; ++k) {
      y(k) = c_ * x;
      const Eigen::Index late = k - whole_delay_;
      const double u_late = late >= 0 ? u(late) : 0.0;
      const double u_early = late - 1 >= 0 ? u(late - 1) : 0.0;
      x = phi_ * x + gamma_early_ * u_early + gamma_late_ * u_late;
    }
  }

 private:
  static void Discretise(const Matrix& a, const Vector& b, double h, Matrix& phi, Vector& gamma) {
    Eigen::Matrix<double, N + 1, N + 1> augmented = Eigen::Matrix<double, N + 1, N + 1>::Zero();
    augmented.template topLeftCorner<N, N>() = a * h;
    augmented.template topRightCorner<N, 1>() = b * h;
    const Eigen::Matrix<double, N + 1, N + 1> e = augmented.exp();
    phi = e.template topLeftCorner<N, N>();
    gamma = e.template topRightCorner<N, 1>();
  }

  Matrix phi_;
  Vector gamma_early_;
  Vector gamma_late_;
  RowVector c_;
  int whole_delay_ = 0;
};

}  // namespace canalid::core
