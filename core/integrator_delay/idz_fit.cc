#include "core/integrator_delay/idz_fit.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/integrator_delay/closed_loop_detector.h"
#include "core/integrator_delay/integrator_delay_model.h"

namespace canalid::core {
namespace {

constexpr int kMinFitSamples = 20;

// [Q - q_in(k - nk), q_in(k - nk), 1, k - k0]: the IDZ level equation's regressors (IdzLevel).
Eigen::MatrixXd IdzRegressors(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                              const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk, int k0) {
  Eigen::MatrixXd x = OpenLoopRegressors(q_in, q_out, nk, k0);
  x.col(0) -= x.col(1);
  return x;
}

// IdzRegressors and, when p22 is fitted, -q_out(k).
Eigen::MatrixXd Regressors(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                           const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk, int k0,
                           bool fit_p22) {
  Eigen::MatrixXd base = IdzRegressors(q_in, q_out, nk, k0);
  if (!fit_p22) return base;
  Eigen::MatrixXd x(base.rows(), 5);
  x.leftCols(4) = base;
  x.col(4) = -q_out.tail(base.rows());
  return x;
}

// The regression with p21 >= 0, as the ID fit: a negative wave-front gain lets the delay slip by a
// sample and means no front; then p21 is held at 0 and its column (1) dropped.
struct ActiveRegression {
  Eigen::MatrixXd x;  // the columns fitted
  bool p21_held = false;
  // Index in x of column c of the full regression (c != 1 when p21 is held).
  Eigen::Index Column(Eigen::Index c) const { return p21_held && c > 1 ? c - 1 : c; }
};

ActiveRegression WithNonNegativeP21(Eigen::MatrixXd x, const Eigen::VectorXd& target) {
  ActiveRegression active;
  if (x.colPivHouseholderQr().solve(target)(1) >= 0.0) {
    active.x = std::move(x);
    return active;
  }
  active.p21_held = true;
  active.x.resize(x.rows(), x.cols() - 1);
  active.x << x.col(0), x.rightCols(x.cols() - 2);
  return active;
}

}  // namespace

Eigen::VectorXd IdzLevel(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                         const Eigen::Ref<const Eigen::VectorXd>& q_out, const IdzLevelModel& model,
                         int k0) {
  if (q_out.size() != q_in.size()) {
    throw std::invalid_argument("IDZ level: q_in and q_out must have the same length");
  }
  const Eigen::Vector4d theta(model.b, model.p21_s_per_m2, model.offset_m,
                              model.drift_m_per_sample);
  const Eigen::MatrixXd x = IdzRegressors(q_in, q_out, model.nk, k0);
  return x * theta - model.p22_s_per_m2 * q_out.tail(x.rows());
}

const char* OutflowGainSourceName(OutflowGainSource source) {
  switch (source) {
    case OutflowGainSource::kData:
      return "data";
    case OutflowGainSource::kPrior:
      return "prior";
    case OutflowGainSource::kNone:
      return "none";
  }
  return "none";
}

IdzFit FitIdz(const Eigen::Ref<const Eigen::VectorXd>& q_in,
              const Eigen::Ref<const Eigen::VectorXd>& q_out,
              const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
              const IdzFitOptions& options) {
  ValidatePoolRecord(q_in, q_out, level, sample_time_s, "IDZ fit");
  const auto n = static_cast<int>(q_in.size());
  const int max_nk = options.max_nk >= 0 ? options.max_nk : n / 3;
  if (options.min_nk < 0 || options.min_nk > max_nk) {
    throw std::invalid_argument("IDZ fit: need 0 <= min_nk <= max_nk (got " +
                                std::to_string(options.min_nk) + ", " + std::to_string(max_nk) +
                                ")");
  }
  const bool has_prior = !(options.p22_prior_s_per_m2 < 0.0);  // NaN: a bad prior, refused
  if (has_prior &&
      (!std::isfinite(options.p22_prior_s_per_m2) ||
       !std::isfinite(options.p22_prior_std_s_per_m2) || options.p22_prior_std_s_per_m2 < 0.0)) {
    throw std::invalid_argument("IDZ fit: the p22 prior and its std must be finite, std >= 0");
  }
  const int k0 = max_nk + 1;
  if (n - k0 < kMinFitSamples) {
    throw std::invalid_argument("IDZ fit: needs at least " + std::to_string(kMinFitSamples) +
                                " samples after the longest delay candidate (" +
                                std::to_string(max_nk) + " samples); the record has " +
                                std::to_string(n));
  }
  IdzFit fit;
  fit.sample_time_s = sample_time_s;
  fit.first_sample = k0;

  // Does the outflow move, and on its own?  The same rule as the ID fit's closed-loop test.
  ClosedLoopDetector detector;
  for (int k = 0; k < n; ++k) detector.AddInflow(q_in(k));
  for (int k = k0; k < n; ++k) detector.AddOutflowLevel(q_out(k), level(k));
  fit.outflow_moves = detector.OutflowMoves();
  fit.outflow_follows_level = detector.ClosedLoop();  // signed: see ClosedLoopDetector
  fit.outflow_level_correlation = detector.OutflowLevelCorrelation();
  std::ostringstream why;
  const bool fit_p22 = fit.outflow_moves && !fit.outflow_follows_level;
  if (fit_p22) {
    fit.p22_source = OutflowGainSource::kData;
    why << "the outflow moved on its own (outflow-level correlation "
        << fit.outflow_level_correlation << ")";
  } else if (has_prior) {
    fit.p22_source = OutflowGainSource::kPrior;
    why << (fit.outflow_moves ? "the outflow followed the level (correlation "
                              : "the outflow was held (correlation ")
        << fit.outflow_level_correlation << "): p22 cannot be told from the data";
  } else {
    fit.p22_source = OutflowGainSource::kNone;
    why << (fit.outflow_moves ? "the outflow followed the level" : "the outflow was held")
        << " and there is no prior";
    if (fit.outflow_moves) {
      fit.warnings.push_back(
          "the outflow follows the level and p22 has no prior: the area reads A (1 + p22 g); "
          "give the pool's p22 (canalid theory's p22_low_frequency_s_per_m2)");
    }
  }
  fit.p22_reason = why.str();
  const double p22_held =
      fit.p22_source == OutflowGainSource::kPrior ? options.p22_prior_s_per_m2 : 0.0;
  const Eigen::VectorXd target = level.tail(n - k0) + p22_held * q_out.tail(n - k0);

  // Delay scan on the full regression.
  fit.loss_by_nk.resize(max_nk - options.min_nk + 1);
  double best = std::numeric_limits<double>::infinity();
  for (int nk = options.min_nk; nk <= max_nk; ++nk) {
    const ActiveRegression a = WithNonNegativeP21(Regressors(q_in, q_out, nk, k0, fit_p22), target);
    const Eigen::VectorXd theta = a.x.colPivHouseholderQr().solve(target);
    const double loss = (a.x * theta - target).squaredNorm() / static_cast<double>(n - k0);
    fit.loss_by_nk(nk - options.min_nk) = loss;
    if (loss < best) {
      best = loss;
      fit.nk = nk;
    }
  }
  const ActiveRegression active =
      WithNonNegativeP21(Regressors(q_in, q_out, fit.nk, k0, fit_p22), target);
  const Eigen::MatrixXd& x = active.x;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  const Eigen::VectorXd theta = qr.solve(target);
  const Eigen::VectorXd residual = x * theta - target;
  const double dof = static_cast<double>(x.rows() - x.cols());
  const double sigma2 = residual.squaredNorm() / dof;
  // (X'X)^-1 from the QR: X P = Q R, so (X'X)^-1 = P R^-1 R^-T P'.
  const Eigen::Index p = x.cols();
  const Eigen::MatrixXd r = qr.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inv = r.inverse();
  const Eigen::MatrixXd cov_permuted = r_inv * r_inv.transpose();
  const Eigen::MatrixXd cov =
      qr.colsPermutation() * cov_permuted * qr.colsPermutation().transpose() * sigma2;
  Eigen::VectorXd variance = cov.diagonal();
  if (fit.p22_source == OutflowGainSource::kPrior) {
    // theta(p22) = X^+ (y + p22 q_out): d theta / d p22 = X^+ q_out.
    const Eigen::VectorXd sensitivity = qr.solve(Eigen::VectorXd(q_out.tail(n - k0)));
    const double s2 = options.p22_prior_std_s_per_m2 * options.p22_prior_std_s_per_m2;
    variance += sensitivity.cwiseAbs2() * s2;
  }
  const double b = theta(0);
  fit.area_m2 = sample_time_s / b;
  fit.area_std_m2 = sample_time_s * std::sqrt(variance(0)) / (b * b);
  if (!active.p21_held) {
    fit.p21_s_per_m2 = theta(1);
    fit.p21_std_s_per_m2 = std::sqrt(variance(1));
  } else {
    fit.warnings.push_back(
        "p21 came out negative and is held at 0: no wave front reaches the level as a jump (a "
        "diffusive pool); the delay is where the level's ramp starts, later than the front's "
        "arrival (canalid theory's delay_low_frequency_s against its delay_s)");
  }
  fit.offset_m = theta(active.Column(2));
  fit.drift_m_per_sample = theta(active.Column(3));
  if (fit_p22) {
    fit.p22_s_per_m2 = theta(active.Column(4));
    fit.p22_std_s_per_m2 = std::sqrt(variance(active.Column(4)));
  } else if (fit.p22_source == OutflowGainSource::kPrior) {
    fit.p22_s_per_m2 = options.p22_prior_s_per_m2;
    fit.p22_std_s_per_m2 = options.p22_prior_std_s_per_m2;
  }
  fit.simulated_level = IdzLevel(q_in, q_out, fit.level_model(), k0);
  fit.metrics = ComputeMetrics(level.tail(n - k0), fit.simulated_level, sample_time_s);
  if (!(b > 0.0)) {
    fit.warnings.push_back(
        "the backwater coefficient b is not positive: the level does not rise with net inflow; "
        "check which columns are inflow, outflow and level");
  }
  if (fit.nk == max_nk && max_nk > options.min_nk) {
    fit.warnings.push_back(
        "the best delay is the longest candidate; allow longer delays (--max-delay-s)");
  }
  return fit;
}

}  // namespace canalid::core
