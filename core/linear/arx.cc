#include "core/linear/arx.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {
namespace {

std::string Str(Eigen::Index v) { return std::to_string(v); }

// Sum over inputs and lags of b_ij u_i(t - nk_i - j); out-of-range past values are zero.
double InputPart(const ArxModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                 Eigen::Index t) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < u.cols(); ++i) {
    const Eigen::VectorXd& b = model.b[static_cast<std::size_t>(i)];
    const Eigen::Index nk = model.orders.nk[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < b.size(); ++j) {
      const Eigen::Index k = t - nk - j;
      if (k >= 0) sum += b(j) * u(k, i);
    }
  }
  return sum;
}

void CheckInputs(const ArxModel& model, Eigen::Index cols, const char* who) {
  if (cols != static_cast<Eigen::Index>(model.b.size())) {
    throw std::invalid_argument(std::string(who) + ": u has " + Str(cols) +
                                " columns, the model has " + Str(Eigen::Index(model.b.size())) +
                                " inputs");
  }
}

}  // namespace

int ArxOrders::num_parameters() const {
  int d = na;
  for (int v : nb) d += v;
  return d;
}

int ArxOrders::min_first_sample() const {
  int first = na;
  for (std::size_t i = 0; i < nb.size() && i < nk.size(); ++i) {
    if (nb[i] > 0) first = std::max(first, nb[i] + nk[i] - 1);
  }
  return first;
}

void ArxOrders::Validate(Eigen::Index num_inputs) const {
  const auto check = [](const std::string& name, long long value, long long max) {
    if (value < 0 || value > max) {
      throw std::invalid_argument("ArxOrders." + name + " = " + std::to_string(value) +
                                  " is out of range (allowed: 0.." + std::to_string(max) + ")");
    }
  };
  check("na", na, kMaxArxOrder);
  if (static_cast<Eigen::Index>(nb.size()) != num_inputs ||
      static_cast<Eigen::Index>(nk.size()) != num_inputs) {
    throw std::invalid_argument("ArxOrders: nb has " + Str(Eigen::Index(nb.size())) +
                                " and nk has " + Str(Eigen::Index(nk.size())) +
                                " entries; both must have one per input (" + Str(num_inputs) + ")");
  }
  long long parameters = na;
  for (std::size_t i = 0; i < nb.size(); ++i) {
    check("nb[" + Str(Eigen::Index(i)) + "]", nb[i], kMaxArxOrder);
    check("nk[" + Str(Eigen::Index(i)) + "]", nk[i], kMaxArxDelaySamples);
    parameters += nb[i];
  }
  if (parameters < 1) {
    throw std::invalid_argument("ArxOrders: na + sum(nb) = 0; the model needs a parameter");
  }
  if (parameters > kMaxArxParameters) {
    throw std::invalid_argument("ArxOrders: na + sum(nb) = " + std::to_string(parameters) +
                                " is out of range (allowed: 1.." +
                                std::to_string(kMaxArxParameters) + ")");
  }
}

Eigen::MatrixXd ArxRegressors(const Eigen::Ref<const Eigen::VectorXd>& y,
                              const Eigen::Ref<const Eigen::MatrixXd>& u, const ArxOrders& orders,
                              Eigen::Index first_sample) {
  const Eigen::Index rows = y.size() - first_sample;
  Eigen::MatrixXd phi(rows, orders.num_parameters());
  // Column-wise copies of shifted segments: each column is one contiguous block of y or u.
  Eigen::Index col = 0;
  for (int j = 1; j <= orders.na; ++j) phi.col(col++) = -y.segment(first_sample - j, rows);
  for (Eigen::Index i = 0; i < u.cols(); ++i) {
    const int nk = orders.nk[static_cast<std::size_t>(i)];
    for (int j = 0; j < orders.nb[static_cast<std::size_t>(i)]; ++j) {
      phi.col(col++) = u.col(i).segment(first_sample - nk - j, rows);
    }
  }
  return phi;
}

ArxModel FitArx(const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::MatrixXd>& u, const ArxOrders& orders,
                Eigen::Index first_sample) {
  orders.Validate(u.cols());
  if (u.rows() != y.size()) {
    throw std::invalid_argument("FitArx: u has " + Str(u.rows()) + " rows, y has " + Str(y.size()) +
                                " samples; they must be equal");
  }
  if (!y.allFinite() || !u.allFinite()) {
    throw std::invalid_argument("FitArx: y or u contains a NaN or infinite value");
  }
  const Eigen::Index min_first = orders.min_first_sample();
  if (first_sample == -1) first_sample = min_first;
  if (first_sample < min_first) {
    throw std::invalid_argument("FitArx: first_sample = " + Str(first_sample) +
                                " must be -1 or >= " + Str(min_first) + " for these orders");
  }
  const int d = orders.num_parameters();
  const Eigen::Index n = y.size() - first_sample;
  if (n <= d) {
    throw std::invalid_argument("FitArx: " + Str(std::max<Eigen::Index>(n, 0)) + " equations for " +
                                Str(d) + " parameters; need more samples than parameters");
  }

  // The QR works in the regressor matrix itself (a copy of it was half the fit's memory: 80 MB
  // for an AR(10) over a million samples); the residual below rebuilds the rows block by block.
  Eigen::MatrixXd phi = ArxRegressors(y, u, orders, first_sample);
  const auto target = y.segment(first_sample, n);
  Eigen::ColPivHouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(phi);
  if (qr.rank() < d) {
    throw std::invalid_argument("FitArx: the regressor matrix has rank " + Str(qr.rank()) + " < " +
                                Str(d) +
                                " parameters: the inputs are not persistently exciting for "
                                "these orders (constant or collinear columns)");
  }

  ArxModel model;
  model.orders = orders;
  model.parameters = qr.solve(target);
  // Each row's product as the whole matrix's would give it (a row's sum runs over the columns in
  // order either way), so the loss is bit for bit the same as with a copy.
  Eigen::VectorXd residual(n);
  constexpr Eigen::Index kBlockRows = 4096;
  for (Eigen::Index r0 = 0; r0 < n; r0 += kBlockRows) {
    const Eigen::Index rows = std::min(kBlockRows, n - r0);
    const Eigen::Index end = first_sample + r0 + rows;
    const Eigen::MatrixXd block =
        ArxRegressors(y.head(end), u.topRows(end), orders, first_sample + r0);
    residual.segment(r0, rows) = target.segment(r0, rows) - block * model.parameters;
  }
  const double ssr = residual.squaredNorm();
  model.first_sample = first_sample;
  model.num_samples = n;
  model.loss = ssr / static_cast<double>(n);
  model.noise_variance = ssr / static_cast<double>(n - d);
  const double ratio = static_cast<double>(d) / static_cast<double>(n);
  model.aic = std::log(model.loss) + 2.0 * ratio;
  model.fpe = model.loss * (1.0 + ratio) / (1.0 - ratio);

  // Phi P = Q R  =>  (Phi^T Phi)^{-1} = P R^{-1} R^{-T} P^T.
  const auto r = qr.matrixR().topLeftCorner(d, d).template triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inv = r.solve(Eigen::MatrixXd::Identity(d, d));
  const Eigen::MatrixXd permuted = r_inv * r_inv.transpose();
  const auto& perm = qr.colsPermutation();
  model.covariance = model.noise_variance * (perm * permuted * perm.transpose());
  model.parameter_std = model.covariance.diagonal().cwiseSqrt();

  model.a = model.parameters.head(orders.na);
  Eigen::Index offset = orders.na;
  for (int nb : orders.nb) {
    model.b.push_back(model.parameters.segment(offset, nb));
    offset += nb;
  }
  return model;
}

Eigen::VectorXd SimulateArx(const ArxModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                            const Eigen::Ref<const Eigen::VectorXd>& y_initial) {
  Eigen::VectorXd y_sim(u.rows());
  SimulateArx(model, u, y_initial, y_sim);
  return y_sim;
}

void SimulateArx(const ArxModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                 const Eigen::Ref<const Eigen::VectorXd>& y_initial,
                 Eigen::Ref<Eigen::VectorXd> y_sim) {
  CheckInputs(model, u.cols(), "SimulateArx");
  if (y_initial.size() > u.rows()) {
    throw std::invalid_argument("SimulateArx: y_initial has " + Str(y_initial.size()) +
                                " samples, more than u (" + Str(u.rows()) + ")");
  }
  const Eigen::Index n = u.rows();
  if (y_sim.size() != n) {
    throw std::invalid_argument("SimulateArx: y_sim has " + Str(y_sim.size()) + " values, u has " +
                                Str(n) + " rows");
  }
  y_sim.head(y_initial.size()) = y_initial;
  for (Eigen::Index t = y_initial.size(); t < n; ++t) {
    double value = InputPart(model, u, t);
    for (Eigen::Index j = 1; j <= model.a.size() && j <= t; ++j)
      value -= model.a(j - 1) * y_sim(t - j);
    y_sim(t) = value;
  }
}

Eigen::VectorXd PredictArx(const ArxModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::MatrixXd>& u) {
  CheckInputs(model, u.cols(), "PredictArx");
  if (u.rows() != y.size()) {
    throw std::invalid_argument("PredictArx: u has " + Str(u.rows()) + " rows, y has " +
                                Str(y.size()) + " samples; they must be equal");
  }
  Eigen::VectorXd y_hat(y.size());
  for (Eigen::Index t = 0; t < y.size(); ++t) {
    double value = InputPart(model, u, t);
    for (Eigen::Index j = 1; j <= model.a.size() && j <= t; ++j) value -= model.a(j - 1) * y(t - j);
    y_hat(t) = value;
  }
  return y_hat;
}

}  // namespace canalid::core
