#include "core/fractional/fractional_foptd_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/fractional_simulator.h"
#include "core/fractional/oustaloup.h"
#include "core/numerics/least_squares.h"
#include "core/numerics/levenberg_marquardt.h"
#include "core/numerics/record_checks.h"

namespace canalid::core {
namespace {

double Median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Unit-gain response to du for (T, alpha, tau); the fit is linear in K.
class UnitResponse {
 public:
  UnitResponse(const Eigen::VectorXd& du, double sample_time_s, double sections_per_decade)
      : du_(du), ts_(sample_time_s), spd_(sections_per_decade), y_(du.size()) {}
  const Eigen::VectorXd& Simulate(double time_constant_s, double alpha, double delay_s) {
    ++count_;
    const FractionalFoptdParams p{1.0, time_constant_s, alpha, delay_s};
    FractionalFoptdFitOptions density;
    density.sections_per_decade = spd_;
    OustaloupFoptdSimulator sim(p, ts_, FitOustaloupBand(p, ts_, du_.size(), density));
    for (Eigen::Index k = 0; k < du_.size(); ++k) {
      y_(k) = sim.output();
      sim.Advance(du_(k));
    }
    return y_;
  }
  int count() const { return count_; }

 private:
  const Eigen::VectorXd& du_;
  double ts_;
  double spd_;
  Eigen::VectorXd y_;
  int count_ = 0;
};

double LeastSquaresGain(const Eigen::VectorXd& s, const Eigen::VectorXd& dy) {
  const double ss = s.squaredNorm();
  return ss > 0.0 ? s.dot(dy) / ss : 0.0;
}

// The rest value is re-estimated with the gain from the whole record (FitOffsetGain), which
// matters when the record starts at the step (one rest sample).

void CheckOptions(const FractionalFoptdFitOptions& o) {
  if (!(o.alpha_min > 0.0 && o.alpha_min < o.alpha_max && o.alpha_max < 2.0)) {
    throw std::invalid_argument("FractionalFoptdFitOptions: alpha bounds [" +
                                std::to_string(o.alpha_min) + ", " + std::to_string(o.alpha_max) +
                                "] must satisfy 0 < min < max < 2");
  }
  if (!(o.sections_per_decade > 0.0 && o.sections_per_decade <= kMaxOustaloupSectionsPerDecade)) {
    throw std::invalid_argument("FractionalFoptdFitOptions: sections_per_decade = " +
                                std::to_string(o.sections_per_decade) +
                                " is out of range (allowed: > 0 and <= 20)");
  }
  if (o.max_iterations < 1) {
    throw std::invalid_argument("FractionalFoptdFitOptions: max_iterations = " +
                                std::to_string(o.max_iterations) + " must be >= 1");
  }
}

}  // namespace

FractionalFoptdFitResult FitFractionalFoptd(const Eigen::Ref<const Eigen::VectorXd>& input,
                                            const Eigen::Ref<const Eigen::VectorXd>& output,
                                            double sample_time_s,
                                            const FractionalFoptdFitOptions& options) {
  CheckOptions(options);
  const Eigen::Index n = input.size();
  CheckRecordLengths("FitFractionalFoptd", n, output.size(), 20);
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
    throw std::invalid_argument(
        "FitFractionalFoptd: sample_time_s = " + std::to_string(sample_time_s) + " must be > 0");
  }
  const double ts = sample_time_s;
  const double record_s = static_cast<double>(n) * ts;

  // Deviations from the initial rest point.
  FractionalFoptdFitResult result;
  result.input_offset = input(0);
  const Eigen::VectorXd du = input.array() - input(0);
  const double du_range = du.cwiseAbs().maxCoeff();
  if (!(du_range > 0.0)) {
    throw std::invalid_argument("FitFractionalFoptd: the input never changes (no excitation)");
  }
  Eigen::Index first_change = 0;
  while (std::abs(du(first_change)) <= 1e-9 * du_range) ++first_change;
  // y[k] depends on u[j < k] only, so y[0..first_change] is still the rest value.
  result.output_offset = output.head(first_change + 1).mean();
  const Eigen::VectorXd dy = output.array() - result.output_offset;

  // Stage 1: static gain from the final value, for a single step only (a PRBS record does not
  // end in a steady state; its gain comes from least squares).
  const Eigen::Index tail = std::max<Eigen::Index>(1, n / 20);
  const double du_final = du.tail(tail).mean();
  const double dy_final = dy.tail(tail).mean();
  int changes = 0;
  for (Eigen::Index k = 1; k < n; ++k) changes += std::abs(du(k) - du(k - 1)) > 1e-9 * du_range;
  const bool ends_away = changes == 1 && std::abs(du_final) > 0.2 * du_range;
  double gain = ends_away ? dy_final / du_final : std::numeric_limits<double>::quiet_NaN();

  // Stage 2: delay from the response start.
  std::vector<double> differences(static_cast<size_t>(n - 1));
  for (Eigen::Index k = 1; k < n; ++k) differences[static_cast<size_t>(k - 1)] = dy(k) - dy(k - 1);
  const double diff_median = Median(differences);
  for (double& d : differences) d = std::abs(d - diff_median);
  const double sigma = 1.4826 * Median(differences) / std::sqrt(2.0);
  double final_change = dy_final;
  if (!ends_away) {
    Eigen::Index at = 0;
    dy.cwiseAbs().maxCoeff(&at);
    final_change = dy(at);
  }
  // A centred 7-sample mean lowers the noise by sqrt(7) so low-SNR steps are still detected
  // near their start; the 2 % floor keeps noise-free records from triggering on rounding.
  constexpr Eigen::Index kHalfWindow = 3;
  const double threshold =
      std::max(4.0 * sigma / std::sqrt(2.0 * kHalfWindow + 1.0), 0.02 * std::abs(final_change));
  auto smoothed = [&](Eigen::Index k) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, k - kHalfWindow);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, k + kHalfWindow);
    return dy.segment(lo, hi - lo + 1).mean();
  };
  double max_delay = options.max_delay_s > 0.0 ? options.max_delay_s : 0.5 * record_s;
  double delay = 0.0;
  for (Eigen::Index k = first_change + 1; k + 4 < n; ++k) {
    bool beyond = true;
    for (Eigen::Index j = k; j < k + 5 && beyond; ++j) beyond = std::abs(smoothed(j)) > threshold;
    if (beyond) {
      // y[k] is the first output past the threshold; the response started before it.
      delay = std::max(0.0, static_cast<double>(k - 1 - first_change) * ts);
      break;
    }
  }
  delay = std::min(delay, max_delay);

  // Stage 3: T and alpha by ISE over a grid (K by least squares when the final value is not
  // usable, otherwise from the final value as the flume paper does).
  UnitResponse unit(du, ts, options.sections_per_decade);
  auto ise = [&](double tc, double a, double tau) {
    const Eigen::VectorXd& s = unit.Simulate(tc, a, tau);
    const double k = ends_away ? gain : LeastSquaresGain(s, dy);
    return (k * s - dy).squaredNorm();
  };
  double best_cost = std::numeric_limits<double>::infinity();
  double best_alpha = 1.0, best_tc = 1.0;
  auto grid = [&]() {
    constexpr int kScales = 12;
    for (double alpha = 0.5; alpha <= 1.5 + 1e-9; alpha += 0.2) {
      const double a = std::clamp(alpha, options.alpha_min, options.alpha_max);
      for (int i = 0; i < kScales; ++i) {
        const double tc = std::pow(ts * std::pow(record_s / ts, (i + 0.5) / kScales), a);
        const double cost = ise(tc, a, delay);
        if (cost < best_cost) {
          best_cost = cost;
          best_alpha = a;
          best_tc = tc;
        }
      }
    }
  };
  grid();
  // The detected start lags the true one when the step is small against the noise: scan
  // earlier delays and redo the grid when one of them is better.
  const double detected = delay;
  for (int i = 0; i < 10; ++i) {
    const double tau = detected * i / 10.0;
    const double cost = ise(best_tc, best_alpha, tau);
    if (cost < best_cost) {
      best_cost = cost;
      delay = tau;
    }
  }
  if (delay != detected) grid();
  if (!ends_away) gain = LeastSquaresGain(unit.Simulate(best_tc, best_alpha, delay), dy);
  result.initial = {gain, best_tc, best_alpha, delay};
  result.params = result.initial;
  result.converged = true;

  // Stage 4: joint refinement; K is the linear least-squares gain for each (T, alpha, tau).
  if (options.refine) {
    auto residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
      const Eigen::VectorXd& s = unit.Simulate(std::exp(p(1) * p(0)), p(1), p(2));
      const OffsetGain og = FitOffsetGain(s, dy);
      r = (og.gain * s - dy).array() + og.offset;
      return r.allFinite();
    };
    Eigen::VectorXd start(3), lower(3), upper(3);
    // p(0) = log of the time scale T^(1/alpha): bounded to [Ts / 100, 10 x record], which keeps
    // unidentifiable records (a response far from settled) from running off to absurd T.
    start << std::log(best_tc) / best_alpha, best_alpha, delay;
    lower << std::log(0.01 * ts), options.alpha_min, 0.0;
    upper << std::log(10.0 * record_s), options.alpha_max, max_delay;
    LmOptions lm;
    lm.max_iterations = options.max_iterations;
    lm.relative_step_tolerance = 1e-7;
    lm.relative_cost_tolerance = 1e-9;
    lm.jacobian_step = 1e-5;
    const LmResult fit = LevenbergMarquardt(residual, start, lower, upper, lm);
    const double tc = std::exp(fit.params(1) * fit.params(0));
    const Eigen::VectorXd& s = unit.Simulate(tc, fit.params(1), fit.params(2));
    const OffsetGain og = FitOffsetGain(s, dy);
    result.output_offset += og.offset;
    result.params = {og.gain, tc, fit.params(1), fit.params(2)};
    result.converged = fit.converged;
  }

  const Eigen::VectorXd& s =
      unit.Simulate(result.params.time_constant_s, result.params.alpha, result.params.delay_s);
  result.simulated = (result.params.gain * s).array() + result.output_offset;
  result.metrics = ComputeMetrics(output, result.simulated, ts);
  result.simulations = unit.count();
  return result;
}

OustaloupOptions FitOustaloupBand(const FractionalFoptdParams& params, double sample_time_s,
                                  Eigen::Index samples, const FractionalFoptdFitOptions& options) {
  OustaloupOptions band =
      DefaultOustaloupOptions(params, sample_time_s, static_cast<double>(samples) * sample_time_s);
  band.sections_per_decade = options.sections_per_decade;
  return band;
}

}  // namespace canalid::core
