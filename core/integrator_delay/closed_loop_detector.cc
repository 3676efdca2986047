#include "core/integrator_delay/closed_loop_detector.h"

#include <algorithm>
#include <cmath>

namespace canalid::core {

void ClosedLoopDetector::Moments::Add(double x) {
  if (n == 0) first = x;
  const double d = x - first;
  sum += d;
  sum2 += d * d;
  ++n;
}

double ClosedLoopDetector::Moments::Variance() const {
  if (n == 0) return 0.0;
  const double m = static_cast<double>(n);
  const double mean = sum / m;
  return std::max(0.0, sum2 / m - mean * mean);
}

void ClosedLoopDetector::AddInflow(double q_in_m3s) { in_.Add(q_in_m3s); }

void ClosedLoopDetector::AddOutflowLevel(double q_out_m3s, double level_m) {
  out_.Add(q_out_m3s);
  if (n_ == 0) level_first_ = level_m;
  const double t = static_cast<double>(n_);
  const double x = q_out_m3s - out_.first;
  const double y = level_m - level_first_;
  st_ += t;
  stt_ += t * t;
  sy_ += y;
  syy_ += y * y;
  sxt_ += x * t;
  syt_ += y * t;
  sxy_ += x * y;
  ++n_;
}

double ClosedLoopDetector::OutflowLevelCorrelation() const {
  if (n_ < 3) return 0.0;
  // Residual inner products after projecting off [1, t]: <ra, rb> = Sab - [Sa Sat] G^-1 [Sb Sbt]',
  // G = [[m, St], [St, Stt]].
  const double m = static_cast<double>(n_);
  const double det = m * stt_ - st_ * st_;
  const double sx = out_.sum;
  auto detrended = [&](double sab, double sa, double sat, double sb, double sbt) {
    return sab - (sa * (stt_ * sb - st_ * sbt) + sat * (-st_ * sb + m * sbt)) / det;
  };
  const double xx = detrended(out_.sum2, sx, sxt_, sx, sxt_);
  const double yy = detrended(syy_, sy_, syt_, sy_, syt_);
  const double xy = detrended(sxy_, sx, sxt_, sy_, syt_);
  const double denominator = std::sqrt(std::max(0.0, xx) * std::max(0.0, yy));
  return denominator > 0.0 ? xy / denominator : 0.0;
}

bool ClosedLoopDetector::OutflowMoves() const {
  return std::sqrt(out_.Variance()) > kOutflowMovesRatio * std::sqrt(in_.Variance());
}

bool ClosedLoopDetector::ClosedLoop() const {
  return OutflowMoves() && OutflowLevelCorrelation() > kCorrelationMin;
}

}  // namespace canalid::core
