#include "core/online/online_three_step.h"

#include <cmath>
#include <stdexcept>

#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("ThreeStepOptions", name, value, range);
}

}  // namespace

bool StableAutoregression(const Eigen::Ref<const Eigen::Matrix<double, 4, 1>>& a, int order) {
  // Step-down (Levinson backwards): with k_p = a_p, A is stable iff |k_p| < 1 and the
  // degree-(p-1) polynomial (a_i - k_p a_{p-i}) / (1 - k_p^2) is stable.
  double c[4] = {a(0), a(1), a(2), a(3)};
  for (int p = order; p >= 1; --p) {
    const double k = c[p - 1];
    if (!std::isfinite(k) || std::abs(k) >= 1.0) return false;
    const double scale = 1.0 / (1.0 - k * k);
    double next[4] = {0.0, 0.0, 0.0, 0.0};
    for (int i = 1; i < p; ++i) next[i - 1] = (c[i - 1] - k * c[p - i - 1]) * scale;
    for (int i = 0; i < 4; ++i) c[i] = next[i];
  }
  return true;
}

void ThreeStepOptions::Validate() const {
  if (sensitivity_order < 1 || sensitivity_order > OnlineThreeStep::kMaxOrder) {
    Fail("sensitivity_order", sensitivity_order, "1..4");
  }
  if (warmup_samples < 0) Fail("warmup_samples", warmup_samples, ">= 0");
  if (recentre_samples < 0) Fail("recentre_samples", recentre_samples, ">= 0");
  sensitivity.Validate(OnlineThreeStep::kSensitivityParams);
  regression.Validate(OnlineThreeStep::kParams);
}

OnlineThreeStep::OnlineThreeStep(const ThreeStepOptions& options)
    : options_((options.Validate(), options)),
      order_(options.sensitivity_order),
      ls_(options.sensitivity),
      iv_(options.sensitivity),
      fit_(options.regression) {}

void OnlineThreeStep::FreezeSensitivity(int order, const Eigen::Ref<const Eigen::VectorXd>& theta) {
  if (order < 1 || order > kMaxOrder) {
    throw std::invalid_argument("FreezeSensitivity: order = " + std::to_string(order) +
                                " is out of range (allowed: 1..4)");
  }
  if (theta.size() != 2 * Eigen::Index{order} || !theta.allFinite()) {
    throw std::invalid_argument(
        "FreezeSensitivity: theta must have 2 x order = " + std::to_string(2 * order) +
        " finite entries (got " + std::to_string(theta.size()) + ")");
  }
  order_ = order;
  f_used_.setZero();
  for (int j = 0; j < order; ++j) {
    f_used_(j) = theta(j);
    f_used_(kMaxOrder + j) = theta(order + j);
  }
  frozen_ = true;
}

bool OnlineThreeStep::Update(double delayed_inflow_m3s, double total_flow_m3s, double level_m,
                             bool level_ok) {
  ++i_;
  const int m = order_;
  for (int j = kMaxOrder; j > 0; --j) u_(j) = u_(j - 1);
  u_(0) = delayed_inflow_m3s;

  // Step (2): the zero-DC-gain ARX on the measured total flow, once m past samples exist.
  if (!frozen_ && i_ >= m) {
    SensitivityVector phi = SensitivityVector::Zero();
    SensitivityVector z = SensitivityVector::Zero();
    for (int j = 0; j < m; ++j) {
      phi(j) = -t_(j);
      z(j) = -t_hat_(j);
      phi(kMaxOrder + j) = z(kMaxOrder + j) = u_(j) - u_(m);
    }
    if (options_.sensitivity_iv) {
      iv_.Update(phi, z, total_flow_m3s);
    } else {
      ls_.Update(phi, total_flow_m3s);
    }
    const SensitivityVector& candidate = options_.sensitivity_iv ? iv_.theta() : ls_.theta();
    // An unstable F_hat would make the simulated flow explode and stay in the fit: keep the
    // last stable one.
    if (StableAutoregression(candidate.head<kMaxOrder>(), m)) {
      f_used_ = candidate;
    } else {
      ++unstable_;
    }
  }

  // Step (3a): the noise-free total flow and the free responses through F_hat.
  double t_hat = 0.0;
  Eigen::Matrix<double, 1, kMaxOrder> free_now = Eigen::Matrix<double, 1, kMaxOrder>::Zero();
  if (i_ < m) {
    free_now(static_cast<int>(i_)) = 1.0;
  } else {
    for (int j = 0; j < m; ++j) {
      t_hat += -f_used_(j) * t_hat_(j) + f_used_(kMaxOrder + j) * (u_(j) - u_(m));
      free_now.noalias() -= f_used_(j) * free_.row(j);
    }
  }
  for (int j = kMaxOrder - 1; j > 0; --j) {
    t_(j) = t_(j - 1);
    t_hat_(j) = t_hat_(j - 1);
    free_.row(j) = free_.row(j - 1);
  }
  t_(0) = total_flow_m3s;
  t_hat_(0) = t_hat;
  free_.row(0) = free_now;
  integrated_(0) += t_hat;
  integrated_.tail<kMaxOrder>() += free_now.transpose();

  // Step (3b): the level against the integrated noise-free flow.
  if (i_ < options_.warmup_samples || !level_ok) return false;
  const double t = static_cast<double>(i_);
  if (options_.recentre_samples > 0 && t - t_centre_ >= options_.recentre_samples) Recentre();
  Eigen::Matrix<double, kParams, 1> phi = Eigen::Matrix<double, kParams, 1>::Zero();
  phi(0) = integrated_(0) - centre_(0);
  if (options_.free_response_terms) {
    for (int r = 0; r < m; ++r) phi(1 + r) = integrated_(1 + r) - centre_(1 + r);
  }
  phi(kOffset) = 1.0;
  phi(kDrift) = t - t_centre_;
  fit_.Update(phi, level_m);
  return true;
}

void OnlineThreeStep::Recentre() {
  // c' = c + b Q_c + sum g_r F_rc + d t_c: an exact linear map of theta (as
  // OnlineIntegratorDelayBank does).
  const double t_new = static_cast<double>(i_);
  Eigen::Matrix<double, kParams, kParams> transform =
      Eigen::Matrix<double, kParams, kParams>::Identity();
  for (int j = 0; j < 1 + kMaxOrder; ++j) transform(kOffset, j) = integrated_(j) - centre_(j);
  transform(kOffset, kDrift) = t_new - t_centre_;
  fit_.Transform(transform);
  centre_ = integrated_;
  t_centre_ = t_new;
}

double OnlineThreeStep::c_m() const {
  const auto& th = fit_.theta();
  return th(kOffset) - th.head<1 + kMaxOrder>().dot(centre_) - th(kDrift) * t_centre_;
}

void OnlineThreeStep::StandardDeviations(double& b_std, double& c_std_m, double& d_std_m) const {
  Eigen::Matrix<double, kParams, kParams> p;
  fit_.Covariance(p);
  const double s2 = fit_.innovation_variance();
  Eigen::Matrix<double, kParams, 1> a = Eigen::Matrix<double, kParams, 1>::Zero();  // c = a' theta
  a.head<1 + kMaxOrder>() = -centre_;
  a(kOffset) = 1.0;
  a(kDrift) = -t_centre_;
  b_std = std::sqrt(std::max(0.0, s2 * p(0, 0)));
  c_std_m = std::sqrt(std::max(0.0, s2 * a.dot(p * a)));
  d_std_m = std::sqrt(std::max(0.0, s2 * p(kDrift, kDrift)));
}

}  // namespace canalid::core
