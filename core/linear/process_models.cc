#include "core/linear/process_models.h"

#include <stdexcept>
#include <string>

#include "core/signal/delayed_zoh.h"

namespace canalid::core {
namespace {

void RequirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(name) + " must be > 0 and finite (got " +
                                std::to_string(value) + ")");
  }
}

}  // namespace

Eigen::VectorXd Simulate(const FoptdModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         double sample_time_s) {
  RequirePositive(model.time_constant_s, "time_constant_s");
  const double t = model.time_constant_s;
  const DelayedZoh<1> system(Eigen::Matrix<double, 1, 1>(-1.0 / t),
                             Eigen::Matrix<double, 1, 1>(model.gain / t),
                             Eigen::Matrix<double, 1, 1>(1.0), sample_time_s, model.delay_s);
  Eigen::VectorXd y(u.size());
  system.Simulate(u, y);
  return y;
}

Eigen::VectorXd Simulate(const SoptdModel& model, const Eigen::Ref<const Eigen::VectorXd>& u,
                         double sample_time_s) {
  RequirePositive(model.time_constants_s[0], "time_constants_s[0]");
  RequirePositive(model.time_constants_s[1], "time_constants_s[1]");
  const double t1 = model.time_constants_s[0];
  const double t2 = model.time_constants_s[1];
  // Cascade: x1' = (K u - x1)/T1, x2' = (x1 - x2)/T2, y = x2 (also exact when T1 == T2).
  Eigen::Matrix2d a;
  a << -1.0 / t1, 0.0, 1.0 / t2, -1.0 / t2;
  const DelayedZoh<2> system(a, Eigen::Vector2d(model.gain / t1, 0.0), Eigen::RowVector2d(0.0, 1.0),
                             sample_time_s, model.delay_s);
  Eigen::VectorXd y(u.size());
  system.Simulate(u, y);
  return y;
}

}  // namespace canalid::core
