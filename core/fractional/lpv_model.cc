#include "core/fractional/lpv_model.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/fractional/fractional_simulator.h"
#include "core/signal/fractional_delay.h"

namespace canalid::core {
namespace {

// A delay in samples carried as a real parameter (a polynomial in theta, or a local fit's nk),
// rounded and clamped below at `min`.  std::lround of a value beyond long (or NaN) is undefined,
// and the count indexes the record, so it is checked against kMaxDelaySamples first.
long DelaySamples(double value, long min, const char* where) {
  if (!(std::abs(value) <= kMaxDelaySamples)) {
    throw std::invalid_argument(std::string(where) + ": delay nk = " + std::to_string(value) +
                                " samples is out of range (allowed: |nk| <= 1e7)");
  }
  return std::max(min, std::lround(value));
}

constexpr const char* kArxName = "first_order_arx";

// y ~ offset + s: the constant that minimises the error (the operating-point level).
double MeanAbsoluteError(const Eigen::VectorXd& y, const Eigen::VectorXd& s) {
  const double offset = (y - s).mean();
  return ((y - s).array() - offset).abs().mean();
}

}  // namespace

LocalModelKind FirstOrderArxKind(int max_delay_samples) {
  if (max_delay_samples < 1) {
    throw std::invalid_argument("FirstOrderArxKind: max_delay_samples = " +
                                std::to_string(max_delay_samples) + " must be >= 1");
  }
  LocalModelKind kind;
  kind.name = kArxName;
  kind.parameter_names = {"a1", "b1", "nk"};
  kind.fit = [max_delay_samples](const Eigen::VectorXd& u, const Eigen::VectorXd& y, double) {
    const Eigen::Index n = u.size();
    if (n < max_delay_samples + 10) {
      throw std::invalid_argument("FirstOrderArxKind: " + std::to_string(n) +
                                  " samples, need at least max_delay_samples + 10");
    }
    double best = std::numeric_limits<double>::infinity();
    Eigen::VectorXd params(3);
    // The same rows for every nk so that residuals compare.
    const Eigen::Index first = max_delay_samples;
    const Eigen::Index rows = n - first;
    Eigen::MatrixXd phi(rows, 3);
    for (int nk = 1; nk <= max_delay_samples; ++nk) {
      for (Eigen::Index r = 0; r < rows; ++r) {
        const Eigen::Index k = first + r;
        phi(r, 0) = -y(k - 1);
        phi(r, 1) = u(k - nk);
        phi(r, 2) = 1.0;
      }
      const Eigen::VectorXd target = y.tail(rows);
      const Eigen::VectorXd theta = phi.colPivHouseholderQr().solve(target);
      const double cost = (phi * theta - target).squaredNorm();
      if (cost < best) {
        best = cost;
        params << theta(0), theta(1), nk;
      }
    }
    return params;
  };
  kind.simulate = [](const Eigen::VectorXd& p, const Eigen::VectorXd& du, double) {
    const long nk = DelaySamples(p(2), 1L, "first-order ARX local");
    Eigen::VectorXd y = Eigen::VectorXd::Zero(du.size());
    for (Eigen::Index k = 1; k < du.size(); ++k) {
      y(k) = -p(0) * y(k - 1) + p(1) * (k - nk >= 0 ? du(k - nk) : 0.0);
    }
    return y;
  };
  return kind;
}

LocalModelKind FractionalFoptdKind(const FractionalFoptdFitOptions& options) {
  LocalModelKind kind;
  kind.name = "frac_foptd";
  kind.parameter_names = {"gain", "time_constant_s", "alpha", "delay_s"};
  kind.fit = [options](const Eigen::VectorXd& u, const Eigen::VectorXd& y, double ts) {
    const FractionalFoptdFitResult r = FitFractionalFoptd(u, y, ts, options);
    Eigen::VectorXd p(4);
    p << r.params.gain, r.params.time_constant_s, r.params.alpha, r.params.delay_s;
    return p;
  };
  kind.simulate = [](const Eigen::VectorXd& p, const Eigen::VectorXd& du, double ts) {
    // Interpolated parameters may leave the model's domain; clamp to it.
    const FractionalFoptdParams params{p(0), std::max(p(1), 1e-6), std::clamp(p(2), 0.05, 1.95),
                                       std::max(p(3), 0.0)};
    return SimulateFractionalFoptd(params, du, ts);
  };
  return kind;
}

LocalModelKind CommensurateKind(int q, int max_delay_samples,
                                const CommensurateFitOptions& options) {
  if (q < 1 || max_delay_samples < 0) {
    throw std::invalid_argument(
        "CommensurateKind: q = " + std::to_string(q) +
        " must be >= 1 and max_delay_samples = " + std::to_string(max_delay_samples) + " >= 0");
  }
  const int n = 2 * q;
  LocalModelKind kind;
  kind.name = "frac_ss_q" + std::to_string(q);
  // Appended, not `"a" + std::to_string(i)`: GCC 12 at -O3 reports a false -Wrestrict through
  // libstdc++'s operator+(const char*, string&&) (GCC bug 105329).
  const auto indexed = [](char prefix, int i) {
    return std::string(1, prefix).append(std::to_string(i));
  };
  for (int i = 1; i <= n; ++i) kind.parameter_names.push_back(indexed('a', i));
  for (int i = 1; i < n; ++i) kind.parameter_names.push_back(indexed('c', i));
  kind.parameter_names.push_back("nk");
  kind.fit = [q, n, max_delay_samples, options](const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                                double ts) {
    const CommensurateFitResult r =
        FitCommensurateScanDelay(u, y, q, max_delay_samples, ts, options);
    Eigen::VectorXd p(2 * n);
    p << r.model.a, r.model.c, r.model.delay_samples;
    return p;
  };
  kind.simulate = [q, n, options](const Eigen::VectorXd& p, const Eigen::VectorXd& du, double) {
    CommensurateModel m;
    m.q = q;
    m.a = p.head(n);
    m.c = p.segment(n, n - 1);
    m.delay_samples = static_cast<int>(DelaySamples(p(2 * n - 1), 0L, "frac-ss local"));
    return SimulateCommensurate(m, du, options.memory_length);
  };
  return kind;
}

LocalModelKind IntegratorWaveKind(const IntegratorWaveFitOptions& options) {
  LocalModelKind kind;
  kind.name = "integrator_wave";
  kind.parameter_names = {"gain", "s_coeff_s2", "m_coeff_s", "delay_s"};
  kind.fit = [options](const Eigen::VectorXd& u, const Eigen::VectorXd& y, double ts) {
    const IntegratorWaveFit r = FitIntegratorWave(u, y, ts, options);
    Eigen::VectorXd p(4);
    p << r.model.gain, r.model.s_coeff_s2, r.model.m_coeff_s, r.model.delay_s;
    return p;
  };
  kind.simulate = [](const Eigen::VectorXd& p, const Eigen::VectorXd& du, double ts) {
    // Interpolated parameters may leave the model's domain; clamp to it.
    const IntegratorWaveModel m{p(0), std::max(p(1), 1e-9), std::max(p(2), 1e-9),
                                std::max(p(3), 0.0)};
    return SimulateIntegratorWave(m, du, ts);
  };
  return kind;
}

double EvaluatePolynomial(const Eigen::Ref<const Eigen::VectorXd>& coefficients, double theta) {
  double value = 0.0;
  for (Eigen::Index i = 0; i < coefficients.size(); ++i) value = value * theta + coefficients(i);
  return value;
}

Eigen::VectorXd FitPolynomial(const Eigen::Ref<const Eigen::VectorXd>& theta,
                              const Eigen::Ref<const Eigen::VectorXd>& values, int degree) {
  if (theta.size() != values.size()) {
    throw std::invalid_argument("FitPolynomial: " + std::to_string(theta.size()) + " thetas but " +
                                std::to_string(values.size()) + " values");
  }
  if (degree < 0 || theta.size() < degree + 1) {
    throw std::invalid_argument("FitPolynomial: degree " + std::to_string(degree) +
                                " needs at least " + std::to_string(degree + 1) + " points, got " +
                                std::to_string(theta.size()));
  }
  const double scale = std::max(theta.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::MatrixXd v(theta.size(), degree + 1);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    for (int j = 0; j <= degree; ++j) v(i, j) = std::pow(theta(i) / scale, degree - j);
  }
  Eigen::VectorXd c = v.colPivHouseholderQr().solve(values);
  for (int j = 0; j <= degree; ++j) c(j) /= std::pow(scale, degree - j);
  return c;
}

Eigen::VectorXd LpvModel::Evaluate(double theta) const {
  Eigen::VectorXd p(coefficients.rows());
  for (Eigen::Index i = 0; i < coefficients.rows(); ++i) {
    p(i) = EvaluatePolynomial(coefficients.row(i).transpose(), theta);
  }
  return p;
}

std::vector<LpvOperatingPoint> SplitByScheduling(const Eigen::Ref<const Eigen::VectorXd>& theta,
                                                 const std::vector<double>& edges) {
  if (edges.size() < 2) {
    throw std::invalid_argument("SplitByScheduling: need at least 2 band edges, got " +
                                std::to_string(edges.size()));
  }
  for (size_t i = 1; i < edges.size(); ++i) {
    if (!(edges[i] > edges[i - 1])) {
      throw std::invalid_argument("SplitByScheduling: edges must increase strictly (edge " +
                                  std::to_string(i) + " = " + std::to_string(edges[i]) + ")");
    }
  }
  std::vector<LpvOperatingPoint> points(edges.size() - 1);
  for (size_t b = 0; b + 1 < edges.size(); ++b) {
    LpvOperatingPoint& p = points[b];
    p.theta_low = edges[b];
    p.theta_high = edges[b + 1];
    Eigen::Index run_start = 0, run_length = 0;
    for (Eigen::Index k = 0; k <= theta.size(); ++k) {
      const bool inside = k < theta.size() && theta(k) >= p.theta_low && theta(k) < p.theta_high;
      if (inside) {
        if (run_length == 0) run_start = k;
        ++run_length;
      } else if (run_length > 0) {
        if (run_length > p.length) {
          p.start = run_start;
          p.length = run_length;
        }
        run_length = 0;
      }
    }
    if (p.length > 0) p.theta_mean = theta.segment(p.start, p.length).mean();
  }
  return points;
}

LpvIdentification IdentifyLpv(const Eigen::Ref<const Eigen::VectorXd>& input,
                              const Eigen::Ref<const Eigen::VectorXd>& output,
                              const Eigen::Ref<const Eigen::VectorXd>& theta, double sample_time_s,
                              const std::vector<double>& edges, const LocalModelKind& kind,
                              int degree, int min_samples) {
  if (output.size() != input.size() || theta.size() != input.size()) {
    throw std::invalid_argument("IdentifyLpv: input, output and theta must have the same length");
  }
  if (!(sample_time_s > 0.0)) {
    throw std::invalid_argument("IdentifyLpv: sample_time_s = " + std::to_string(sample_time_s) +
                                " must be > 0");
  }
  LpvIdentification result;
  for (LpvOperatingPoint& p : SplitByScheduling(theta, edges)) {
    if (p.length < min_samples) continue;
    const Eigen::VectorXd u = input.segment(p.start, p.length);
    const Eigen::VectorXd y = output.segment(p.start, p.length);
    try {
      p.local_params = kind.fit(u, y, sample_time_s);
    } catch (const std::invalid_argument& e) {
      // Name the band: one without excitation (an input held through it) stops the whole fit.
      throw std::invalid_argument("IdentifyLpv: the band of samples " + std::to_string(p.start) +
                                  ".." + std::to_string(p.start + p.length - 1) + ": " + e.what());
    }
    const Eigen::VectorXd du = u.array() - u(0);
    p.local_mae = MeanAbsoluteError(y, kind.simulate(p.local_params, du, sample_time_s));
    result.points.push_back(p);
  }
  const int used = static_cast<int>(result.points.size());
  if (used < degree + 1) {
    throw std::invalid_argument("IdentifyLpv: " + std::to_string(used) + " bands with at least " +
                                std::to_string(min_samples) + " samples; degree " +
                                std::to_string(degree) + " needs " + std::to_string(degree + 1));
  }
  const Eigen::Index num_params = result.points.front().local_params.size();
  Eigen::VectorXd thetas(used);
  Eigen::MatrixXd values(used, num_params);
  for (int i = 0; i < used; ++i) {
    thetas(i) = result.points[static_cast<size_t>(i)].theta_mean;
    values.row(i) = result.points[static_cast<size_t>(i)].local_params.transpose();
  }
  LpvModel& model = result.model;
  model.kind = kind.name;
  model.parameter_names = kind.parameter_names;
  model.degree = degree;
  model.coefficients.resize(num_params, degree + 1);
  for (Eigen::Index j = 0; j < num_params; ++j) {
    model.coefficients.row(j) = FitPolynomial(thetas, values.col(j), degree).transpose();
  }
  for (LpvOperatingPoint& p : result.points) {
    const Eigen::VectorXd u = input.segment(p.start, p.length);
    const Eigen::VectorXd y = output.segment(p.start, p.length);
    const Eigen::VectorXd du = u.array() - u(0);
    p.lpv_mae =
        MeanAbsoluteError(y, kind.simulate(model.Evaluate(p.theta_mean), du, sample_time_s));
  }
  return result;
}

Eigen::VectorXd SimulateLpvArx(const LpvModel& model, const Eigen::Ref<const Eigen::VectorXd>& du,
                               const Eigen::Ref<const Eigen::VectorXd>& theta) {
  if (model.kind != kArxName || model.coefficients.rows() != 3) {
    throw std::invalid_argument("SimulateLpvArx: model kind '" + model.kind + "' is not " +
                                kArxName);
  }
  if (du.size() != theta.size()) {
    throw std::invalid_argument("SimulateLpvArx: du and theta must have the same length");
  }
  Eigen::VectorXd y = Eigen::VectorXd::Zero(du.size());
  for (Eigen::Index k = 1; k < du.size(); ++k) {
    const double a1 = EvaluatePolynomial(model.coefficients.row(0).transpose(), theta(k));
    const double b1 = EvaluatePolynomial(model.coefficients.row(1).transpose(), theta(k));
    // At least one sample, as documented: a polynomial extrapolated below 0.5 would otherwise
    // read du(k) or beyond the end of the record.
    const long nk = DelaySamples(
        EvaluatePolynomial(model.coefficients.row(2).transpose(), theta(k)), 1L, "SimulateLpvArx");
    y(k) = -a1 * y(k - 1) + b1 * (k - nk >= 0 ? du(k - nk) : 0.0);
  }
  return y;
}

}  // namespace canalid::core
