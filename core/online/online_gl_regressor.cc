#include "core/online/online_gl_regressor.h"

#include <algorithm>
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
  weights_.resize(static_cast<std::size_t>(memory) + 1);
  weights_[0] = 1.0;
  for (int j = 1; j <= memory; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    weights_[uj] = weights_[uj - 1] * (1.0 - (alpha + 1.0) / j);
  }
}

double OnlineGlRegressor::Sum(const RingBuffer<double>& history) const {
  const int terms = std::min(memory(), history.size());
  double s = 0.0;
  for (int j = 1; j <= terms; ++j) s += weights_[static_cast<std::size_t>(j)] * history[j - 1];
  return s;
}

}  // namespace canalid::core
