#include "core/linear/arx_delay_scan.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>

namespace canalid::core {

ArxModel FitArxOverDelays(const Eigen::Ref<const Eigen::VectorXd>& y,
                          const Eigen::Ref<const Eigen::VectorXd>& u, int na, int nb, int min_nk,
                          int max_nk) {
  if (!(min_nk >= 1 && min_nk <= max_nk && max_nk <= kMaxArxDelaySamples)) {
    throw std::invalid_argument("arx delay range [" + std::to_string(min_nk) + ", " +
                                std::to_string(max_nk) + "] samples (allowed: 1 <= min <= max)");
  }
  if (u.size() != y.size()) throw std::invalid_argument("arx: u and y differ in length");
  ArxOrders widest;
  widest.na = na;
  widest.nb = {nb};
  widest.nk = {max_nk};
  widest.Validate(1);
  const Eigen::Index first = widest.min_first_sample();
  std::optional<ArxModel> best;
  for (int nk = min_nk; nk <= max_nk; ++nk) {
    ArxOrders orders = widest;
    orders.nk = {nk};
    ArxModel model = FitArx(y, u, orders, first);
    if (!best || model.loss < best->loss) best = std::move(model);
  }
  return *best;
}

}  // namespace canalid::core
