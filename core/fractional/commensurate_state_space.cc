#include "core/fractional/commensurate_state_space.h"

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/grunwald_letnikov.h"
#include "core/numerics/levenberg_marquardt.h"
#include "core/numerics/record_checks.h"

namespace canalid::core {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// [D^b s](k) = sum_{j=0..k} w_j^(b) s(k-j), full memory (b = 0 is the identity).
Eigen::VectorXd FractionalDifference(const Eigen::VectorXd& s, double order) {
  const Eigen::Index n = s.size();
  if (order == 0.0) return s;
  const Eigen::VectorXd w = GrunwaldLetnikovWeights(order, static_cast<int>(n));
  Eigen::VectorXd d(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    d(k) = w.head(k + 1).dot(s.head(k + 1).reverse());
  }
  return d;
}

// Value at index k, zero before the record starts (at rest).
double At(const Eigen::VectorXd& s, Eigen::Index k) { return k >= 0 ? s(k) : 0.0; }

}  // namespace

void Validate(const CommensurateModel& model) {
  if (model.q < 1) {
    throw std::invalid_argument("CommensurateModel: q = " + std::to_string(model.q) +
                                " must be >= 1");
  }
  const int n = model.order();
  if (model.a.size() != n || model.c.size() != n - 1) {
    throw std::invalid_argument("CommensurateModel: q = " + std::to_string(model.q) + " needs " +
                                std::to_string(n) + " a and " + std::to_string(n - 1) +
                                " c coefficients, got " + std::to_string(model.a.size()) + " and " +
                                std::to_string(model.c.size()));
  }
  if (model.delay_samples < 0) {
    throw std::invalid_argument("CommensurateModel: delay_samples = " +
                                std::to_string(model.delay_samples) + " must be >= 0");
  }
  if (!model.a.allFinite() || !model.c.allFinite()) {
    throw std::invalid_argument("CommensurateModel: coefficients must be finite");
  }
}

namespace {

// What one simulation needs besides its result, kept between calls of a delay scan: the GL
// weights (they depend on alpha and the record's length only) and the states' history.
struct SimulationBuffers {
  Eigen::VectorXd weights;
  RowMajorMatrix history;
  Eigen::VectorXd x, next;
};

// The GL weights SimulateInto uses for `steps` samples with memory L (0: full).
Eigen::Index SimulationMemory(Eigen::Index steps, int memory_length) {
  return memory_length > 0 ? memory_length : steps + 1;
}
void PrepareWeights(double alpha, Eigen::Index steps, int memory_length, SimulationBuffers& b) {
  const Eigen::Index memory = SimulationMemory(steps, memory_length);
  b.weights = GrunwaldLetnikovWeights(alpha, static_cast<int>(std::min(memory, steps + 1) + 1));
}

// SimulateCommensurate's recursion into `output`, with b.weights from PrepareWeights for this
// model's alpha and the input's length.  Resizes the buffers only when the sizes change.
void SimulateInto(const CommensurateModel& model, const Eigen::Ref<const Eigen::VectorXd>& input,
                  int memory_length, SimulationBuffers& b, Eigen::VectorXd& output) {
  const int n = model.order();
  const Eigen::Index steps = input.size();
  const Eigen::Index memory = SimulationMemory(steps, memory_length);
  const Eigen::VectorXd& w = b.weights;
  // history(i, steps - k) = x_i[k]: time runs backwards along a row so that the GL sum for x[k+1]
  // is one contiguous dot product per state.  Every column read is written first, at an
  // earlier step of this call, so the history needs no clearing.
  b.history.resize(n, steps + 1);
  b.x.setZero(n);
  b.next.resize(n);
  output.resize(steps);
  Eigen::VectorXd& x = b.x;
  Eigen::VectorXd& next = b.next;
  const double a_n = model.a(n - 1);
  for (Eigen::Index k = 0; k < steps; ++k) {
    output(k) = x(0) + model.c.dot(x.tail(n - 1));
    b.history.col(steps - k) = x;
    // A x: shift up, last row -sum a_{n-j} x_{j}.
    next.head(n - 1) = x.tail(n - 1);
    next(n - 1) = -model.a.reverse().dot(x);
    const Eigen::Index ki = k - model.delay_samples;
    next(n - 1) += a_n * (ki >= 0 ? input(ki) : 0.0);
    // - sum_{j=1..min(k+1, L)} w_j x[k+1-j]; x[k+1-j] sits at column steps - k - 1 + j.
    const Eigen::Index terms = std::min<Eigen::Index>(k + 1, memory);
    for (int i = 0; i < n; ++i) {
      next(i) -= w.segment(1, terms).dot(b.history.row(i).segment(steps - k, terms));
    }
    x = next;
  }
}

}  // namespace

Eigen::VectorXd SimulateCommensurate(const CommensurateModel& model,
                                     const Eigen::Ref<const Eigen::VectorXd>& input,
                                     int memory_length) {
  Validate(model);
  if (memory_length < 0) {
    throw std::invalid_argument(
        "SimulateCommensurate: memory_length = " + std::to_string(memory_length) + " must be >= 0");
  }
  SimulationBuffers buffers;
  PrepareWeights(model.alpha(), input.size(), memory_length, buffers);
  Eigen::VectorXd output;
  SimulateInto(model, input, memory_length, buffers, output);
  return output;
}

namespace {

// The GL differences of du and dy needed by the least-squares recursion (independent of nk).
struct Differences {
  Eigen::VectorXd du, dy;
  std::vector<Eigen::VectorXd> dy_orders;  // [D^{i alpha} dy], i = 0..n
  std::vector<Eigen::VectorXd> du_orders;  // [D^{m alpha} du], m = 0..n-1
};

Differences ComputeDifferences(const Eigen::VectorXd& du, const Eigen::VectorXd& dy, int q) {
  const int n = 2 * q;
  const double alpha = 1.0 / q;
  Differences d{du, dy, {}, {}};
  for (int i = 0; i <= n; ++i) d.dy_orders.push_back(FractionalDifference(dy, i * alpha));
  for (int m = 0; m < n; ++m) d.du_orders.push_back(FractionalDifference(du, m * alpha));
  return d;
}

// The equation-error least squares' buffers, kept between the candidates of a delay scan (the
// regressor is the record's length times 2n - 1).
struct LeastSquaresBuffers {
  Eigen::MatrixXd phi;
  Eigen::VectorXd target;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  Eigen::VectorXd rotated;  // Q' target
  Eigen::VectorXd theta;
};

// Equation-error least squares into `model` (q and the delay set, a and c resized only when q
// changes).  Columns: a_1..a_n, g_1..g_{n-1} (g_m = a_n c_m).  The solve is Eigen's
// ColPivHouseholderQR::solve step by step, into the buffers instead of fresh vectors.
void LeastSquaresModel(const Differences& d, int q, int delay_samples, LeastSquaresBuffers& b,
                       CommensurateModel& model) {
  const int n = 2 * q;
  const Eigen::Index steps = d.du.size();
  b.phi.resize(steps, 2 * n - 1);
  b.target.resize(steps);
  for (Eigen::Index k = 0; k < steps; ++k) {
    b.target(k) = -d.dy_orders[static_cast<size_t>(n)](k);
    for (int i = 1; i < n; ++i) {
      b.phi(k, i - 1) = At(d.dy_orders[static_cast<size_t>(n - i)], k - i);
    }
    b.phi(k, n - 1) = At(d.dy, k - n) - At(d.du, k - n - delay_samples);
    for (int m = 1; m < n; ++m) {
      b.phi(k, n - 1 + m) = -At(d.du_orders[static_cast<size_t>(m)], k - n + m - delay_samples);
    }
  }
  b.qr.compute(b.phi);
  const Eigen::Index pivots = b.qr.nonzeroPivots();
  b.theta.setZero(2 * n - 1);
  if (pivots > 0) {
    // Q' target, reflector by reflector as Eigen's HouseholderSequence applies them to one
    // column (the same operations, so the same bits), without its temporary per reflector.
    b.rotated = b.target;
    for (Eigen::Index k = 0; k < pivots; ++k) {
      const double tau = b.qr.hCoeffs()(k);
      if (tau == 0.0) continue;
      const auto essential = b.qr.matrixQR().col(k).tail(steps - k - 1);
      auto bottom = b.rotated.tail(steps - k - 1);
      const double w = essential.dot(bottom) + b.rotated(k);
      b.rotated(k) -= tau * w;
      for (Eigen::Index i = 0; i < bottom.size(); ++i) bottom(i) -= (tau * essential(i)) * w;
    }
    b.qr.matrixQR()
        .topLeftCorner(pivots, pivots)
        .triangularView<Eigen::Upper>()
        .solveInPlace(b.rotated.head(pivots));
    for (Eigen::Index i = 0; i < pivots; ++i) {
      b.theta(b.qr.colsPermutation().indices()(i)) = b.rotated(i);
    }
  }
  model.q = q;
  model.delay_samples = delay_samples;
  model.a = b.theta.head(n);
  const double a_n = model.a(n - 1);
  if (a_n != 0.0) {
    model.c = b.theta.tail(n - 1) / a_n;
  } else {
    model.c.setZero(n - 1);
  }
}

CommensurateModel LeastSquaresModel(const Differences& d, int q, int delay_samples) {
  LeastSquaresBuffers buffers;
  CommensurateModel model;
  LeastSquaresModel(d, q, delay_samples, buffers, model);
  return model;
}

// Stage 2 (the LPV paper): LM on the simulation error, and the result's bookkeeping.
CommensurateFitResult Refine(const CommensurateModel& model, const Eigen::VectorXd& du,
                             const Eigen::VectorXd& dy,
                             const Eigen::Ref<const Eigen::VectorXd>& input,
                             const Eigen::Ref<const Eigen::VectorXd>& output, double sample_time_s,
                             const CommensurateFitOptions& options) {
  const int n = model.order();
  CommensurateFitResult result;
  result.input_offset = input(0);
  result.output_offset = output(0);
  result.initial = model;
  result.model = model;
  result.converged = true;
  Eigen::VectorXd simulated = SimulateCommensurate(model, du, options.memory_length);
  // An unstable least-squares model cannot start the refinement; it is returned as it is.
  if (options.refine && simulated.allFinite() && (simulated - dy).squaredNorm() < 1e100) {
    auto unpack = [&](const Eigen::VectorXd& p) {
      CommensurateModel m = model;
      m.a = p.head(n);
      m.c = p.tail(n - 1);
      return m;
    };
    auto residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
      r = SimulateCommensurate(unpack(p), du, options.memory_length) - dy;
      return r.allFinite() && r.squaredNorm() < 1e100;
    };
    Eigen::VectorXd start(2 * n - 1);
    start << model.a, model.c;
    const Eigen::VectorXd inf =
        Eigen::VectorXd::Constant(2 * n - 1, std::numeric_limits<double>::infinity());
    LmOptions lm;
    lm.max_iterations = options.max_iterations;
    const LmResult fit = LevenbergMarquardt(residual, start, -inf, inf, lm);
    result.model = unpack(fit.params);
    result.converged = fit.converged;
    simulated = SimulateCommensurate(result.model, du, options.memory_length);
  }
  result.simulated = simulated.array() + result.output_offset;
  result.metrics = ComputeMetrics(output, result.simulated, sample_time_s);
  return result;
}

void CheckFitArguments(const char* where, Eigen::Index input_size, Eigen::Index output_size, int q,
                       int delay_samples, double sample_time_s) {
  const std::string w(where);
  if (q < 1) throw std::invalid_argument(w + ": q = " + std::to_string(q) + " must be >= 1");
  if (delay_samples < 0) {
    throw std::invalid_argument(w + ": delay_samples = " + std::to_string(delay_samples) +
                                " must be >= 0");
  }
  if (!(sample_time_s > 0.0)) {
    throw std::invalid_argument(w + ": sample_time_s = " + std::to_string(sample_time_s) +
                                " must be > 0");
  }
  CheckRecordLengths(where, input_size, output_size, 20 * q + delay_samples);
}

// A record whose input never leaves u[0] has no deviation to fit: the least-squares problem is
// singular and the refinement would start from nothing.
void CheckInputMoves(const char* where, const Eigen::Ref<const Eigen::VectorXd>& input) {
  if ((input.array() == input(0)).all()) {
    throw std::invalid_argument(std::string(where) +
                                ": the input never moves from its first value");
  }
}

}  // namespace

CommensurateFitResult FitCommensurate(const Eigen::Ref<const Eigen::VectorXd>& input,
                                      const Eigen::Ref<const Eigen::VectorXd>& output, int q,
                                      int delay_samples, double sample_time_s,
                                      const CommensurateFitOptions& options) {
  CheckFitArguments("FitCommensurate", input.size(), output.size(), q, delay_samples,
                    sample_time_s);
  CheckInputMoves("FitCommensurate", input);
  const Eigen::VectorXd du = input.array() - input(0);
  const Eigen::VectorXd dy = output.array() - output(0);
  const Differences d = ComputeDifferences(du, dy, q);
  return Refine(LeastSquaresModel(d, q, delay_samples), du, dy, input, output, sample_time_s,
                options);
}

CommensurateFitResult FitCommensurateScanDelay(const Eigen::Ref<const Eigen::VectorXd>& input,
                                               const Eigen::Ref<const Eigen::VectorXd>& output,
                                               int q, int max_delay_samples, double sample_time_s,
                                               const CommensurateFitOptions& options) {
  CheckFitArguments("FitCommensurateScanDelay", input.size(), output.size(), q, max_delay_samples,
                    sample_time_s);
  CheckInputMoves("FitCommensurateScanDelay", input);
  const Eigen::VectorXd du = input.array() - input(0);
  const Eigen::VectorXd dy = output.array() - output(0);
  const Differences d = ComputeDifferences(du, dy, q);
  // One set of buffers for every candidate: no record-length allocation per delay.
  LeastSquaresBuffers least_squares;
  SimulationBuffers simulation;
  PrepareWeights(1.0 / q, du.size(), options.memory_length, simulation);
  CommensurateModel candidate;
  Eigen::VectorXd simulated;
  double best = std::numeric_limits<double>::infinity();
  CommensurateModel chosen;
  LeastSquaresModel(d, q, 0, least_squares, chosen);
  for (int nk = 0; nk <= max_delay_samples; ++nk) {
    LeastSquaresModel(d, q, nk, least_squares, candidate);
    Validate(candidate);
    SimulateInto(candidate, du, options.memory_length, simulation, simulated);
    const double cost = (simulated - dy).squaredNorm();
    if (std::isfinite(cost) && cost < best) {
      best = cost;
      chosen = candidate;
    }
  }
  return Refine(chosen, du, dy, input, output, sample_time_s, options);
}

}  // namespace canalid::core
