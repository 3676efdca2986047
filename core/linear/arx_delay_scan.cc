#include "core/linear/arx_delay_scan.h"

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
  // The delay of least loss on the common window by the projected scan (ScanArxDelay: one
  // factorisation of the output lags for all candidates, memory bounded), then the model at it.
  ArxDelayScanOptions scan;
  scan.orders = widest;
  scan.min_nk = min_nk;
  scan.max_nk = max_nk;
  const ArxDelayScan delays = ScanArxDelay(y, u, scan);
  ArxOrders orders = widest;
  orders.nk = {delays.best_nk};
  return FitArx(y, u, orders, widest.min_first_sample());
}

}  // namespace canalid::core
