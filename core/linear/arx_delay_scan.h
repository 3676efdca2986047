#pragma once
#include <Eigen/Core>

#include "core/linear/arx.h"
#include "core/linear/delay_estimation.h"

namespace canalid::core {

/// The single-input ARX model of orders na, nb (ArxOrders) whose delay nk in [min_nk, max_nk]
/// gives the smallest loss V.  Every candidate is fitted on the same equations (from the first
/// sample the largest delay allows), so their losses compare.  Ties keep the smaller delay.  The
/// delay comes from ScanArxDelay (the output lags factorised once, the candidates in bounded
/// memory), the model from FitArx at it.
/// @throws std::invalid_argument for bad orders or range (1 <= min_nk <= max_nk), sizes that
///         differ, a record too short for max_nk, an input that does not move or output lags that
///         are not persistently exciting (ScanArxDelay's and FitArx's errors).
ArxModel FitArxOverDelays(const Eigen::Ref<const Eigen::VectorXd>& y,
                          const Eigen::Ref<const Eigen::VectorXd>& u, int na, int nb, int min_nk,
                          int max_nk);

}  // namespace canalid::core
