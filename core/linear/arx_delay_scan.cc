#include "core/linear/arx_delay_scan.h"

#include <stdexcept>
#include <string>

#include "core/linear/delay_estimation.h"

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
  // ScanArxDelay's losses are FitArx's on the same equations (first sample the largest delay
  // allows), computed from one factorisation of the output lags; the best delay is then fitted.
  ArxDelayScanOptions scan_options;
  scan_options.orders = widest;
  scan_options.min_nk = min_nk;
  scan_options.max_nk = max_nk;
  const ArxDelayScan scan = ScanArxDelay(y, u, scan_options);
  ArxOrders orders = widest;
  orders.nk = {scan.best_nk};
  return FitArx(y, u, orders, scan.first_sample);
}

}  // namespace canalid::core
