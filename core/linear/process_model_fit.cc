#include "core/linear/process_model_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/numerics/least_squares.h"
#include "core/numerics/levenberg_marquardt.h"

namespace canalid::core {
namespace {

struct Problem {
  Eigen::VectorXd u;  // deviation input
  double u0 = 0.0;    // the input value the deviations are taken from
  Eigen::VectorXd y;  // measured output
  double ts = 1.0;
  double max_delay_s = 0.0;
  double min_time_constant_s = 0.0;
  double max_time_constant_s = 0.0;
};

Problem MakeProblem(const Eigen::Ref<const Eigen::VectorXd>& u,
                    const Eigen::Ref<const Eigen::VectorXd>& y, double ts,
                    const ProcessFitOptions& options) {
  if (u.size() != y.size()) throw std::invalid_argument("process fit: u and y differ in length");
  if (u.size() < 10) {
    throw std::invalid_argument("process fit: needs at least 10 samples, got " +
                                std::to_string(u.size()));
  }
  if (!(ts > 0.0)) throw std::invalid_argument("process fit: sample time must be > 0");
  if (!u.allFinite() || !y.allFinite()) throw std::invalid_argument("process fit: non-finite data");
  Problem p;
  p.u0 = u(0);
  p.u = u.array() - p.u0;
  if (p.u.cwiseAbs().maxCoeff() == 0.0)
    throw std::invalid_argument("process fit: the input never moves");
  p.y = y;
  p.ts = ts;
  const double duration = ts * static_cast<double>(u.size());
  p.max_delay_s =
      options.max_delay_s > 0.0 ? std::min(options.max_delay_s, duration / 2.0) : duration / 3.0;
  p.min_time_constant_s = ts / 20.0;
  p.max_time_constant_s = 20.0 * duration;
  return p;
}

// Residual y - (K s + c) for a unit-gain response s; K, c eliminated.
template <class Model, class MakeModel>
ResidualFunction MakeResidual(const Problem& p, MakeModel make_model) {
  return [&p, make_model](const Eigen::VectorXd& params, Eigen::VectorXd& r) {
    const Model model = make_model(params);
    const Eigen::VectorXd s = Simulate(model, p.u, p.ts);
    const OffsetGain lin = FitOffsetGain(s, p.y);
    r = (lin.gain * s).array() + lin.offset - p.y.array();
    return true;
  };
}

template <class Model>
ProcessFit<Model> Finish(const Problem& p, Model unit_model, int iterations) {
  const Eigen::VectorXd s = Simulate(unit_model, p.u, p.ts);
  const OffsetGain lin = FitOffsetGain(s, p.y);
  ProcessFit<Model> fit;
  fit.model = unit_model;
  fit.model.gain = lin.gain;
  fit.output_offset = lin.offset;
  fit.input_offset = p.u0;
  fit.simulated = (lin.gain * s).array() + lin.offset;
  fit.metrics = ComputeMetrics(p.y, fit.simulated, p.ts);
  fit.iterations = iterations;
  return fit;
}

FoptdModel UnitFoptd(const Eigen::VectorXd& params) {
  return FoptdModel{1.0, std::exp(params(0)), params(1)};
}

SoptdModel UnitSoptd(const Eigen::VectorXd& params) {
  return SoptdModel{1.0, {std::exp(params(0)), std::exp(params(1))}, params(2)};
}

double Cost(const ResidualFunction& f, const Eigen::VectorXd& params) {
  Eigen::VectorXd r;
  f(params, r);
  return r.squaredNorm();
}

}  // namespace

FoptdFit FitFoptd(const Eigen::Ref<const Eigen::VectorXd>& u,
                  const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                  const ProcessFitOptions& options) {
  const Problem p = MakeProblem(u, y, sample_time_s, options);
  const ResidualFunction f = MakeResidual<FoptdModel>(p, UnitFoptd);
  // Coarse grid: log-spaced time constants, evenly spaced delays; the LM refinement is local, so
  // the grid must be fine enough in tau to land in the right valley.
  constexpr int kTimeConstants = 14;
  constexpr int kDelays = 41;
  Eigen::VectorXd best(2);
  double best_cost = std::numeric_limits<double>::infinity();
  const double log_lo = std::log(std::max(p.ts / 2.0, p.min_time_constant_s));
  const double log_hi = std::log(p.ts * static_cast<double>(p.u.size()));
  for (int i = 0; i < kTimeConstants; ++i) {
    for (int j = 0; j < kDelays; ++j) {
      Eigen::VectorXd params(2);
      params << log_lo + (log_hi - log_lo) * i / (kTimeConstants - 1),
          p.max_delay_s * j / (kDelays - 1);
      const double c = Cost(f, params);
      if (c < best_cost) {
        best_cost = c;
        best = params;
      }
    }
  }
  const Eigen::Vector2d lower(std::log(p.min_time_constant_s), 0.0);
  const Eigen::Vector2d upper(std::log(p.max_time_constant_s), p.max_delay_s);
  const LmResult lm = LevenbergMarquardt(f, best, lower, upper);
  return Finish(p, UnitFoptd(lm.params), lm.iterations);
}

SoptdFit FitSoptd(const Eigen::Ref<const Eigen::VectorXd>& u,
                  const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                  const ProcessFitOptions& options) {
  const FoptdFit first = FitFoptd(u, y, sample_time_s, options);
  const Problem p = MakeProblem(u, y, sample_time_s, options);
  const ResidualFunction f = MakeResidual<SoptdModel>(p, UnitSoptd);
  // Start points around the FOPTD fit: split T into T1 + T2 for several ratios and take part of
  // the FOPTD delay back (an S-shaped response is fitted by FOPTD with a longer delay).
  const double t_f = first.model.time_constant_s;
  const double tau_f = first.model.delay_s;
  Eigen::VectorXd best(3);
  double best_cost = std::numeric_limits<double>::infinity();
  for (const double ratio : {0.02, 0.1, 0.25, 0.5, 1.0}) {
    const double t1 = t_f / (1.0 + ratio);
    const double t2 = std::max(ratio * t1, p.min_time_constant_s);
    for (const double back : {0.0, 0.5, 1.0}) {
      Eigen::VectorXd params(3);
      params << std::log(t1), std::log(t2), std::clamp(tau_f - back * t2, 0.0, p.max_delay_s);
      const double c = Cost(f, params);
      if (c < best_cost) {
        best_cost = c;
        best = params;
      }
    }
  }
  const Eigen::Vector3d lower(std::log(p.min_time_constant_s), std::log(p.min_time_constant_s),
                              0.0);
  const Eigen::Vector3d upper(std::log(p.max_time_constant_s), std::log(p.max_time_constant_s),
                              p.max_delay_s);
  const LmResult lm = LevenbergMarquardt(f, best, lower, upper);
  SoptdModel unit = UnitSoptd(lm.params);
  if (unit.time_constants_s[0] < unit.time_constants_s[1]) {
    std::swap(unit.time_constants_s[0], unit.time_constants_s[1]);
  }
  return Finish(p, unit, lm.iterations);
}

}  // namespace canalid::core
