#include "core/online/online_gl_regressor.h"

#include <Eigen/Core>

#include <algorithm>
#include <span>
#include <sstream>
#include <stdexcept>

namespace canalid::core {

OnlineGlRegressor::OnlineGlRegressor(double alpha, int memory) : alpha_(alpha) {
  if (!(alpha > 0.0 && alpha < 2.0)) {
    std::ostringstream m;
    m << "OnlineGlRegressor: alpha = " << alpha << " is out of range (allowed: 0 < alpha < 2)";
    throw std::invalid_argument(m.str());
  }
  if (memory < 1) {
    throw std::invalid_argument("OnlineGlRegressor: memory = " + std::to_string(memory) +
                                " is out of range (allowed: >= 1)");
  }
  // w_j = w_{j-1} (1 - (alpha + 1) / j) from w_0 = 1, stored from w_L down to w_1.
  reversed_.resize(static_cast<std::size_t>(memory));
  double w = 1.0;
  for (int j = 1; j <= memory; ++j) {
    w *= 1.0 - (alpha + 1.0) / j;
    reversed_[static_cast<std::size_t>(memory - j)] = w;
  }
}

double OnlineGlRegressor::Sum(const RingBuffer<double>& history) const {
  const int terms = std::min(memory(), history.size());
  // x(k-terms) .. x(k-1) (oldest first) against w_terms .. w_1: the last `terms` reversed weights.
  const RingBuffer<double>::Runs runs = history.Chronological(terms);
  const double* w = reversed_.data() + (reversed_.size() - static_cast<std::size_t>(terms));
  const auto dot = [](const double* a, std::span<const double> x) {
    if (x.empty()) return 0.0;
    const auto n = static_cast<Eigen::Index>(x.size());
    return Eigen::Map<const Eigen::VectorXd>(a, n).dot(
        Eigen::Map<const Eigen::VectorXd>(x.data(), n));
  };
  return dot(w, runs.older) + dot(w + runs.older.size(), runs.newer);
}

}  // namespace canalid::core
