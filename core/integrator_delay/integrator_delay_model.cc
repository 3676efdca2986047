#include "core/integrator_delay/integrator_delay_model.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/integrator_delay/closed_loop_detector.h"
#include "core/numerics/least_squares.h"
#include "core/signal/detrend.h"

namespace canalid::core {
namespace {

constexpr int kMinFitSamples = 20;
constexpr int kSensitivityOrder = 4;

Eigen::VectorXd Detrended(const Eigen::VectorXd& v) { return RemoveLinearTrend(v).detrended; }

double Correlation(const Eigen::VectorXd& a_d, const Eigen::VectorXd& b_d) {
  const double denominator = a_d.norm() * b_d.norm();
  return denominator > 0.0 ? a_d.dot(b_d) / denominator : 0.0;
}

double StandardDeviation(const Eigen::VectorXd& v) {
  return std::sqrt((v.array() - v.mean()).square().sum() / static_cast<double>(v.size()));
}

// Step (2) of the three-step method: the total flow predicted from the delayed inflow alone,
// through an ARX of order m (up to 4) with zero DC gain (at steady state an inflow change has
// all left the pool, so the total flow returns to zero):
//   t(k) = -sum_{i=1..m} a_i t(k-i) + sum_{j=0..m-1} b_j (u(k-j) - u(k-m))      (b_m = -sum b_j).
// The measured total flow carries the outflow meter's noise, which is output noise, not equation
// error, so plain least squares biases the a_i.  Instrumental variables fix that: the lagged
// outputs are instrumented by the outputs simulated from the previous estimate (refined twice,
// as in the IV4 family).  An order above the true one makes the instruments nearly collinear,
// so every order is tried and the one with the lowest simulation error (the output-error
// criterion) among the stable ones is kept.
class SensitivityModel {
 public:
  SensitivityModel(const Eigen::VectorXd& u, int order) : u_(&u), order_(order) {}

  /// Fits to the measured total flow t; false if the estimate is unusable (unstable).
  bool Fit(const Eigen::VectorXd& t) {
    const Eigen::Index rows = t.size() - order_;
    Eigen::MatrixXd x(rows, 2 * order_);
    const Eigen::VectorXd target = t.tail(rows);
    FillRegressors(t, x);
    theta_ = SolveLeastSquares(x, target).theta;
    Eigen::MatrixXd z(rows, 2 * order_);
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::VectorXd simulated = Simulate();
      if (!simulated.allFinite() ||
          simulated.cwiseAbs().maxCoeff() > 1e3 * (t.cwiseAbs().maxCoeff() + 1.0)) {
        return false;
      }
      FillRegressors(simulated, z);
      theta_ = (z.transpose() * x).colPivHouseholderQr().solve(z.transpose() * target);
    }
    const Eigen::VectorXd simulated = Simulate();
    if (!simulated.allFinite() ||
        simulated.cwiseAbs().maxCoeff() > 1e3 * (t.cwiseAbs().maxCoeff() + 1.0)) {
      return false;
    }
    simulation_error_ = (simulated - t).squaredNorm();
    return true;
  }

  double simulation_error() const { return simulation_error_; }
  int order() const { return order_; }
  const Eigen::VectorXd& theta() const { return theta_; }

  /// Noise-free total flow from the inflow alone, from a zero initial state.
  Eigen::VectorXd Simulate() const { return Simulate(-1); }

  /// The m free responses of the autoregressive part (one initial output set to 1): the total
  /// flow's unknown initial state is a combination of them.
  Eigen::MatrixXd FreeResponses() const {
    Eigen::MatrixXd free(u_->size(), order_);
    for (int i = 0; i < order_; ++i) free.col(i) = Simulate(i);
    return free;
  }

 private:
  // initial_one < 0: forced response from rest; otherwise the free response with t(initial_one)
  // = 1.
  Eigen::VectorXd Simulate(int initial_one) const {
    const Eigen::Index n = u_->size();
    Eigen::VectorXd simulated = Eigen::VectorXd::Zero(n);
    const double input_gain = initial_one < 0 ? 1.0 : 0.0;
    if (initial_one >= 0) simulated(initial_one) = 1.0;
    for (Eigen::Index k = order_; k < n; ++k) {
      double value = 0.0;
      for (int i = 1; i <= order_; ++i) value -= theta_(i - 1) * simulated(k - i);
      for (int j = 0; j < order_; ++j) value += input_gain * theta_(order_ + j) * InputTerm(k, j);
      simulated(k) = value;
    }
    return simulated;
  }

  double InputTerm(Eigen::Index k, int j) const { return (*u_)(k - j) - (*u_)(k - order_); }

  // Rows k = m..n-1 of [-t(k-1) .. -t(k-m), u terms] with `t` the (measured or simulated) output.
  void FillRegressors(const Eigen::VectorXd& t, Eigen::MatrixXd& x) const {
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      const Eigen::Index k = r + order_;
      for (int i = 1; i <= order_; ++i) x(r, i - 1) = -t(k - i);
      for (int j = 0; j < order_; ++j) x(r, order_ + j) = InputTerm(k, j);
    }
  }

  const Eigen::VectorXd* u_;  // not owned; outlives the model
  int order_;
  Eigen::VectorXd theta_;
  double simulation_error_ = std::numeric_limits<double>::infinity();
};

struct TotalFlowModel {
  Eigen::VectorXd flow;            // noise-free total flow from the inflow, from rest
  Eigen::MatrixXd free_responses;  // homogeneous solutions (unknown initial state)
  int order = 0;                   // 0: no usable model, the measured flow is used
  Eigen::VectorXd theta;
};

TotalFlowModel NoiseFreeTotalFlow(const Eigen::VectorXd& delayed_inflow_d,
                                  const Eigen::VectorXd& total_flow_d) {
  std::optional<SensitivityModel> best;
  for (int order = 1; order <= kSensitivityOrder; ++order) {
    SensitivityModel candidate(delayed_inflow_d, order);
    if (candidate.Fit(total_flow_d) &&
        (!best || candidate.simulation_error() < best->simulation_error())) {
      best = candidate;
    }
  }
  // Order 1 cannot fail to be stable unless the data are degenerate; fall back to the measured
  // flow.
  if (!best) return {total_flow_d, Eigen::MatrixXd(total_flow_d.size(), 0), 0, {}};
  return {best->Simulate(), best->FreeResponses(), best->order(), best->theta()};
}

// Least squares on [Q, q_in(k-nk), 1, k] with the wave-front gain p21 >= 0 (a jump *up* when the
// inflow rises).  Without the sign constraint, (nk - 1, p21 = -b) reproduces (nk, p21 = 0)
// exactly, so the delay would be ambiguous by one sample.  One inequality: the optimum is the
// unconstrained one, or the fit with the column removed.
LeastSquaresSolution FitWaveFrontNonNegative(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  LeastSquaresSolution fit = SolveLeastSquares(x, y);
  if (fit.theta(1) >= 0.0) return fit;
  Eigen::MatrixXd reduced(x.rows(), 3);
  reduced << x.col(0), x.col(2), x.col(3);
  const LeastSquaresSolution constrained = SolveLeastSquares(reduced, y);
  fit.theta << constrained.theta(0), 0.0, constrained.theta(1), constrained.theta(2);
  fit.residual_sum_of_squares = constrained.residual_sum_of_squares;
  return fit;
}

// The delay scan: the loss of every candidate nk over the rows k0..N-1 in one pass over the
// data per candidate, with no allocation per candidate.  The loss is the mean squared residual
// of y_d (the detrended level) on Q_nk and w_nk = q_in(k - nk), both detrended (the
// Frisch-Waugh-Lovell reduction of [Q, w, 1, k]), with the coefficient of w >= 0.  It is
// computed from the inner products of the raw columns: with c the centred row index,
//   <x_d, z_d> = <x, z> - <x, 1><z, 1> / m - <x, c><z, c> / <c, c>,
// and <x_d, y_d> likewise with y_d's own sums.  Q is accumulated as the integral of
// v - v_mean (v_mean from prefix sums of the flows), which is Q less a straight line: that
// leaves Q_d unchanged and keeps the sums small (no cancellation from Q's drift).  The pass
// streams q_in, q_out and y_d once where the detrended-vector form (one vector per column,
// Gram-Schmidt) made about eight record-length passes and allocations per candidate: on 1M
// samples it was memory-bound, 2.6 x the per-sample cost of 100k.  Equal to a QR solution of the
// same problem to 1e-9 relative (OnlineIdWaveFront.NonNegativeWaveFrontEqualsTheBatchAtEveryDelay).
class DelayScan final {
 public:
  DelayScan(const Eigen::Ref<const Eigen::VectorXd>& q_in,
            const Eigen::Ref<const Eigen::VectorXd>& q_out, int k0, const Eigen::VectorXd& y_d)
      : q_in_(q_in), q_out_(q_out), k0_(k0), y_d_(y_d), m_(y_d.size()) {
    const double m = static_cast<double>(m_);
    c_mean_ = 0.5 * (m - 1.0);
    for (Eigen::Index i = 0; i < m_; ++i) {
      const double c = static_cast<double>(i) - c_mean_;
      cc_ += c * c;
      y_sum_ += y_d(i);
      cy_ += c * y_d(i);
    }
    yy_ = y_d.squaredNorm();
    prefix_in_.resize(q_in.size() + 1);
    prefix_in_(0) = 0.0;
    for (Eigen::Index k = 0; k < q_in.size(); ++k) prefix_in_(k + 1) = prefix_in_(k) + q_in(k);
    // The outflow's part of v is the same for every candidate: q_out(k0 - 1 .. N - 2).
    out_sum_ = q_out.segment(k0 - 1, m_).sum();
  }

  double Loss(int nk) {
    const double m = static_cast<double>(m_);
    // Mean of v = q_in(k - nk) - q_out(k - 1) and of w = q_in(k - nk) over the rows.
    const double w_mean = (prefix_in_(k0_ - nk + m_) - prefix_in_(k0_ - nk)) / m;
    const double v_mean = w_mean - out_sum_ / m;
    const double* in = q_in_.data() + (k0_ - nk);
    const double* out = q_out_.data() + (k0_ - 1);
    const double* y = y_d_.data();
    double q = 0.0;
    double sq = 0.0, cq = 0.0, qq = 0.0, sw = 0.0, cw = 0.0, ww = 0.0, qw = 0.0, qy = 0.0, wy = 0.0;
    for (Eigen::Index i = 0; i < m_; ++i) {
      const double c = static_cast<double>(i) - c_mean_;
      const double w = in[i] - w_mean;
      q += (in[i] - out[i]) - v_mean;
      sq += q;
      cq += c * q;
      qq += q * q;
      sw += w;
      cw += c * w;
      ww += w * w;
      qw += q * w;
      qy += q * y[i];
      wy += w * y[i];
    }
    const double qq_d = qq - sq * sq / m - cq * cq / cc_;
    const double ww_d = ww - sw * sw / m - cw * cw / cc_;
    const double qw_d = qw - sq * sw / m - cq * cw / cc_;
    const double qy_d = qy - sq * y_sum_ / m - cq * cy_ / cc_;
    const double wy_d = wy - sw * y_sum_ / m - cw * cy_ / cc_;
    if (!(qq_d > 0.0)) return yy_ / m;
    const double one_column_rss = yy_ - qy_d * qy_d / qq_d;
    // w less its projection on Q: |r|^2 and <r, y>.  A negative coefficient of w (the sign of
    // <r, y>) is refitted without w (the constraint); an r of no length adds nothing.
    const double rr = ww_d - qw_d * qw_d / qq_d;
    const double ry = wy_d - qw_d * qy_d / qq_d;
    if (!(rr > 1e-24 * ww_d) || ry < 0.0) return one_column_rss / m;
    return (one_column_rss - ry * ry / rr) / m;
  }

 private:
  Eigen::Ref<const Eigen::VectorXd> q_in_;
  Eigen::Ref<const Eigen::VectorXd> q_out_;
  int k0_;
  const Eigen::VectorXd& y_d_;
  Eigen::Index m_;
  double c_mean_ = 0.0;
  double cc_ = 0.0;
  double y_sum_ = 0.0;
  double cy_ = 0.0;
  double yy_ = 0.0;
  double out_sum_ = 0.0;
  Eigen::VectorXd prefix_in_;
};

Eigen::VectorXd CumulativeSum(const Eigen::VectorXd& v) {
  Eigen::VectorXd s(v.size());
  double total = 0.0;
  for (Eigen::Index k = 0; k < v.size(); ++k) s(k) = total += v(k);
  return s;
}

}  // namespace

void ValidatePoolRecord(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                        const Eigen::Ref<const Eigen::VectorXd>& q_out,
                        const Eigen::Ref<const Eigen::VectorXd>& level, double ts,
                        const std::string& what) {
  if (q_in.size() != q_out.size() || q_in.size() != level.size()) {
    throw std::invalid_argument(what + ": q_in, q_out and level must have the same length");
  }
  if (!(ts > 0.0)) throw std::invalid_argument(what + ": sample time must be > 0");
  if (!q_in.allFinite() || !q_out.allFinite() || !level.allFinite()) {
    throw std::invalid_argument(what + ": data contain NaN or Inf");
  }
  if (q_in.maxCoeff() == q_in.minCoeff()) {
    throw std::invalid_argument(
        what + ": the inflow never moves, so neither delay nor area can be identified");
  }
}

Eigen::VectorXd IntegratedTotalFlow(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                    const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk,
                                    int k0) {
  if (nk < 0 || k0 < nk || k0 < 1 || k0 >= q_in.size()) {
    throw std::invalid_argument("IntegratedTotalFlow: need 0 <= nk <= k0, 1 <= k0 < N");
  }
  const Eigen::Index n = q_in.size() - k0;
  Eigen::VectorXd q(n);
  double total = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = k0 + i;
    total += q_in(k - nk) - q_out(k - 1);
    q(i) = total;
  }
  return q;
}

Eigen::MatrixXd OpenLoopRegressors(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                   const Eigen::Ref<const Eigen::VectorXd>& q_out, int nk, int k0) {
  const Eigen::Index rows = q_in.size() - k0;
  Eigen::MatrixXd x(rows, 4);
  x.col(0) = IntegratedTotalFlow(q_in, q_out, nk, k0);
  x.col(1) = q_in.segment(k0 - nk, rows);
  x.col(2).setOnes();
  x.col(3) = Eigen::VectorXd::LinSpaced(rows, 0.0, static_cast<double>(rows - 1));
  return x;
}

IntegratorDelayFit FitIntegratorDelay(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                                      const Eigen::Ref<const Eigen::VectorXd>& q_out,
                                      const Eigen::Ref<const Eigen::VectorXd>& level,
                                      double sample_time_s,
                                      const IntegratorDelayFitOptions& options) {
  ValidatePoolRecord(q_in, q_out, level, sample_time_s, "ID fit");
  const auto n = static_cast<int>(q_in.size());
  const int max_nk = options.max_nk >= 0 ? options.max_nk : n / 3;
  if (options.min_nk < 0 || options.min_nk > max_nk) {
    throw std::invalid_argument("ID fit: need 0 <= min_nk <= max_nk (got " +
                                std::to_string(options.min_nk) + ", " + std::to_string(max_nk) +
                                ")");
  }
  const int k0 = max_nk + 1;
  if (n - k0 < kMinFitSamples) {
    throw std::invalid_argument("ID fit: needs at least " + std::to_string(kMinFitSamples) +
                                " samples after the longest delay candidate (" +
                                std::to_string(max_nk) + " samples); the record has " +
                                std::to_string(n));
  }
  IntegratorDelayFit result;
  result.first_sample = k0;
  result.model.sample_time_s = sample_time_s;
  const Eigen::VectorXd y_d = Detrended(level.tail(n - k0));

  // Delay scan.  The wave front reaches the level sensor as a jump (IDZ's p21), which an
  // integrator alone fits by pulling the delay short and the area small; the inflow term
  // p21 q_in(k - nk) takes the jump, so nk and b describe the integrating part.
  // Each candidate's loss comes from the Frisch-Waugh-Lovell reduction: with y and both varying
  // columns detrended (projected off [1, k]), the residual is that of a 2-column least-squares
  // problem, whose loss DelayScan computes from one pass of inner products.  The chosen nk is
  // then refitted in full (QR).
  result.loss_by_nk.resize(max_nk - options.min_nk + 1);
  const Eigen::VectorXd y_fit = level.tail(n - k0);
  double best_loss = std::numeric_limits<double>::infinity();
  DelayScan scan(q_in, q_out, k0, y_d);
  for (int nk = options.min_nk; nk <= max_nk; ++nk) {
    const double loss = scan.Loss(nk);
    result.loss_by_nk(nk - options.min_nk) = loss;
    if (loss < best_loss) {
      best_loss = loss;
      result.model.nk = nk;
    }
  }
  const int nk = result.model.nk;
  const LeastSquaresSolution open_loop =
      FitWaveFrontNonNegative(OpenLoopRegressors(q_in, q_out, nk, k0), y_fit);
  result.model.b = open_loop.theta(0);
  result.wave_front_gain_s_per_m2 = open_loop.theta(1);
  result.open_loop_area_m2 = sample_time_s / result.model.b;

  // Closed-loop detection: does the outflow follow the level?
  const Eigen::VectorXd q_out_d = Detrended(q_out.tail(n - k0));
  result.outflow_level_correlation = Correlation(q_out_d, y_d);
  const bool outflow_moves = StandardDeviation(q_out.tail(n - k0)) > 0.02 * StandardDeviation(q_in);
  switch (options.closed_loop) {
    case ClosedLoopMode::kOn:
    case ClosedLoopMode::kThreeStep:
      result.closed_loop = true;
      result.closed_loop_reason = "requested";
      break;
    case ClosedLoopMode::kOff:
      result.closed_loop = false;
      result.closed_loop_reason = "disabled";
      break;
    case ClosedLoopMode::kAuto:
      // Signed: a level-driven outflow rises with the level; one moved on its own lowers it.
      result.closed_loop =
          outflow_moves && result.outflow_level_correlation > ClosedLoopDetector::kCorrelationMin;
      result.closed_loop_reason = std::string(outflow_moves ? "outflow moves" : "outflow held") +
                                  ", outflow-level correlation " +
                                  std::to_string(result.outflow_level_correlation);
      break;
  }

  // Instruments and the noise-free total flow need the delayed inflow and total flow per sample.
  Eigen::VectorXd delayed_inflow(n - k0);
  Eigen::VectorXd total_flow(n - k0);
  for (int k = k0; k < n; ++k) {
    delayed_inflow(k - k0) = q_in(k - nk);
    total_flow(k - k0) = q_in(k - nk) - q_out(k - 1);
  }
  const Eigen::VectorXd measured_q_d = Detrended(CumulativeSum(total_flow));
  const Eigen::VectorXd instrument_d =
      Detrended(CumulativeSum((delayed_inflow.array() - delayed_inflow.mean()).matrix()));
  const double iv_denominator = instrument_d.dot(measured_q_d);
  const double b_iv = iv_denominator != 0.0 ? instrument_d.dot(y_d) / iv_denominator : 0.0;
  result.iv_area_m2 = b_iv != 0.0 ? sample_time_s / b_iv : 0.0;

  // Open loop: the scan's regression is the fit.  Closed loop: the three-step regressors, the
  // integrated noise-free total flow plus the integrated free responses of the sensitivity
  // model (they absorb its unknown initial state).  The wave-front term is left out there: with
  // a moving outflow its partner p22 q_out would be needed, and q_out follows the level itself.
  Eigen::MatrixXd x;
  if (result.closed_loop) {
    const TotalFlowModel flow_model =
        NoiseFreeTotalFlow(Detrended(delayed_inflow), Detrended(total_flow));
    const Eigen::Index free = flow_model.free_responses.cols();
    result.sensitivity_order = flow_model.order;
    result.sensitivity_theta = flow_model.theta;
    x.resize(n - k0, 3 + free);
    x.col(0) = CumulativeSum(flow_model.flow);
    for (Eigen::Index i = 0; i < free; ++i)
      x.col(1 + i) = CumulativeSum(flow_model.free_responses.col(i));
    x.col(1 + free).setOnes();
    x.col(2 + free) = Eigen::VectorXd::LinSpaced(n - k0, 0.0, n - k0 - 1.0);
    result.wave_front_gain_s_per_m2 = 0.0;
  } else {
    x = OpenLoopRegressors(q_in, q_out, nk, k0);
  }
  const LeastSquaresSolution fit =
      result.closed_loop ? SolveLeastSquares(x, y_fit) : FitWaveFrontNonNegative(x, y_fit);
  result.model.b = fit.theta(0);
  result.offset_m = fit.theta(x.cols() - 2);
  result.drift_m_per_sample = fit.theta(x.cols() - 1);
  result.simulated_level = x * fit.theta;
  result.metrics = ComputeMetrics(level.tail(n - k0), result.simulated_level, sample_time_s);

  if (!(result.model.b > 0.0)) {
    result.warnings.push_back(
        "the backwater coefficient b is not positive: the level does not rise with net "
        "inflow; check which columns are inflow, outflow and level");
  }
  if (nk == max_nk && max_nk > options.min_nk) {
    result.warnings.push_back(
        "the best delay is the longest candidate; allow longer delays (--max-delay-s)");
  }
  if (result.iv_area_m2 > 0.0 &&
      std::abs(result.iv_area_m2 / result.model.area_m2() - 1.0) > 0.25) {
    result.warnings.push_back(
        "the instrumental-variable area differs from the fit by more than 25 %");
  }
  return result;
}

}  // namespace canalid::core
