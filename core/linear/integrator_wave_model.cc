#include "core/linear/integrator_wave_model.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/numerics/least_squares.h"
#include "core/numerics/levenberg_marquardt.h"
#include "core/numerics/record_checks.h"
#include "core/signal/fractional_delay.h"
#include "core/signal/fractional_zoh.h"

namespace canalid::core {
namespace {

// Unit-gain response (k = 1) of 1/(s (S s^2 + M s + 1)) with delay.
Eigen::VectorXd UnitResponse(double s2, double m, double delay_s, const Eigen::VectorXd& u,
                             double ts) {
  Eigen::Matrix3d a;
  a << 0.0, 1.0, 0.0, -1.0 / s2, -m / s2, 0.0, 1.0, 0.0, 0.0;
  const Eigen::Vector3d b(0.0, 1.0 / s2, 0.0);
  const ZohDelaySplit split = SplitZohDelay(delay_s, ts);
  const ZohSplitModel zoh = DiscretizeZohSplit(a, b, ts, split.fraction);
  const Eigen::Matrix3d phi = zoh.phi;
  const Eigen::Vector3d gp = zoh.gamma_previous;
  const Eigen::Vector3d gc = zoh.gamma_current;
  ZohDelayLine line(split.whole_samples);
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::VectorXd y(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    y(k) = x(2);
    line.Push(u(k));
    x = phi * x + gp * line.previous() + gc * line.current();
  }
  return y;
}

}  // namespace

void Validate(const IntegratorWaveModel& model) {
  if (!std::isfinite(model.gain)) {
    throw std::invalid_argument("IntegratorWaveModel: gain must be finite");
  }
  if (!(model.s_coeff_s2 > 0.0) || !std::isfinite(model.s_coeff_s2)) {
    throw std::invalid_argument(
        "IntegratorWaveModel: s_coeff_s2 = " + std::to_string(model.s_coeff_s2) + " must be > 0");
  }
  if (!(model.m_coeff_s > 0.0) || !std::isfinite(model.m_coeff_s)) {
    throw std::invalid_argument(
        "IntegratorWaveModel: m_coeff_s = " + std::to_string(model.m_coeff_s) + " must be > 0");
  }
  if (!(model.delay_s >= 0.0) || !std::isfinite(model.delay_s)) {
    throw std::invalid_argument("IntegratorWaveModel: delay_s = " + std::to_string(model.delay_s) +
                                " must be >= 0");
  }
}

Eigen::VectorXd SimulateIntegratorWave(const IntegratorWaveModel& model,
                                       const Eigen::Ref<const Eigen::VectorXd>& input,
                                       double sample_time_s) {
  Validate(model);
  if (!(sample_time_s > 0.0)) {
    throw std::invalid_argument("SimulateIntegratorWave: sample_time_s = " +
                                std::to_string(sample_time_s) + " must be > 0");
  }
  return model.gain *
         UnitResponse(model.s_coeff_s2, model.m_coeff_s, model.delay_s, input, sample_time_s);
}

IntegratorWaveFit FitIntegratorWave(const Eigen::Ref<const Eigen::VectorXd>& input,
                                    const Eigen::Ref<const Eigen::VectorXd>& output,
                                    double sample_time_s, const IntegratorWaveFitOptions& options) {
  const Eigen::Index n = input.size();
  CheckRecordLengths("FitIntegratorWave", n, output.size(), 20);
  if (!(sample_time_s > 0.0)) {
    throw std::invalid_argument(
        "FitIntegratorWave: sample_time_s = " + std::to_string(sample_time_s) + " must be > 0");
  }
  const double ts = sample_time_s;
  const Eigen::VectorXd du = input.array() - input(0);
  if (!(du.cwiseAbs().maxCoeff() > 0.0)) {
    throw std::invalid_argument("FitIntegratorWave: the input never changes (no excitation)");
  }
  IntegratorWaveFit result;
  result.input_offset = input(0);
  const double y_first = output(0);
  const Eigen::VectorXd dy = output.array() - y_first;
  const double record_s = static_cast<double>(n) * ts;
  const double max_delay =
      options.max_delay_s > 0.0 ? options.max_delay_s : std::min(0.25 * record_s, 100.0 * ts);

  auto cost = [&](double s2, double m, double tau) {
    const Eigen::VectorXd s = UnitResponse(s2, m, tau, du, ts);
    const OffsetGain og = FitOffsetGain(s, dy);
    return ((og.gain * s - dy).array() + og.offset).matrix().squaredNorm();
  };
  double best = std::numeric_limits<double>::infinity();
  double best_s2 = 1.0, best_m = 1.0, best_tau = 0.0;
  const double tau_step = std::max(ts, max_delay / 40.0);
  for (double tau = 0.0; tau <= max_delay + 1e-9; tau += tau_step) {
    for (int i = 0; i < 8; ++i) {
      const double w = (10.0 / record_s) * std::pow(record_s / (10.0 * ts), i / 7.0);
      for (double zeta : {0.4, 0.8, 1.5}) {
        const double s2 = 1.0 / (w * w);
        const double m = 2.0 * zeta / w;
        const double c = cost(s2, m, tau);
        if (c < best) {
          best = c;
          best_s2 = s2;
          best_m = m;
          best_tau = tau;
        }
      }
    }
  }
  auto residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    const Eigen::VectorXd s = UnitResponse(std::exp(p(0)), std::exp(p(1)), p(2), du, ts);
    const OffsetGain og = FitOffsetGain(s, dy);
    r = (og.gain * s - dy).array() + og.offset;
    return r.allFinite();
  };
  Eigen::VectorXd start(3), lower(3), upper(3);
  start << std::log(best_s2), std::log(best_m), best_tau;
  const double inf = std::numeric_limits<double>::infinity();
  lower << -inf, -inf, 0.0;
  upper << inf, inf, max_delay;
  LmOptions lm;
  lm.max_iterations = options.max_iterations;
  const LmResult fit = LevenbergMarquardt(residual, start, lower, upper, lm);
  const Eigen::VectorXd s =
      UnitResponse(std::exp(fit.params(0)), std::exp(fit.params(1)), fit.params(2), du, ts);
  const OffsetGain og = FitOffsetGain(s, dy);
  result.model = {og.gain, std::exp(fit.params(0)), std::exp(fit.params(1)), fit.params(2)};
  result.output_offset = y_first + og.offset;
  result.simulated = (og.gain * s).array() + result.output_offset;
  result.metrics = ComputeMetrics(output, result.simulated, ts);
  result.converged = fit.converged;
  return result;
}

}  // namespace canalid::core
