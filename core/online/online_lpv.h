#pragma once
#include <cstdint>

#include "core/numerics/ring_buffer.h"
#include "core/online/online_arx.h"
#include "core/online/rls.h"

namespace canalid::core {

/// phi (x) [1, s, s^2]: out(3 i + m) = phi(i) s^m.  @pre out.size() == 3 phi.size().
template <typename D1, typename D2>
void LpvExpand(const Eigen::MatrixBase<D1>& phi, double s, const Eigen::MatrixBase<D2>& out_const) {
  auto& out = const_cast<Eigen::MatrixBase<D2>&>(out_const);
  for (int i = 0; i < phi.size(); ++i) {
    out(3 * i) = phi(i);
    out(3 * i + 1) = phi(i) * s;
    out(3 * i + 2) = phi(i) * s * s;
  }
}

struct OnlineLpvArxOptions {
  int na = 1;             ///< >= 0
  int nb = 1;             ///< >= 1, na + nb <= kMaxOnlineArxParams
  int delay_samples = 1;  ///< nk >= 0
  RlsOptions rls;         ///< n = 3 (na + nb)
  double input_abs_max = 1e9;
  double output_abs_max = 1e9;
  double scheduling_abs_max = 1e9;

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// One-shot LPV ARX (docs/references.md): every ARX coefficient is a quadratic in the
/// scheduling variable s(k) (e.g. the upstream level), p(s) = p0 + p1 s + p2 s^2, estimated online
/// by regressing y(k) on phi(k) (x) [1, s(k), s(k)^2] with phi(k) the ARX regressor of
/// OnlineArxBank (MATLAB convention, rows from k = max(na, nk + nb - 1)).  theta is ordered
/// [a1_0, a1_1, a1_2, a2_0, ..., b1_0, b1_1, b1_2, ...].  A bad u, y or s keeps every regression
/// containing it out of the estimator.  Allocates only in the constructor.  Deterministic.
class OnlineLpvArx final {
 public:
  /// @throws std::invalid_argument on a bad option.
  explicit OnlineLpvArx(const OnlineLpvArxOptions& options);

  /// One sample of input, output and scheduling variable.  True when the estimator was updated.
  bool Update(double u, double y, double scheduling);

  /// The local ARX model at scheduling value s: a(s), b(s) (no allocation).
  void ParametersAt(double s, ArxParamVector& a, ArxParamVector& b) const;
  const Rls<Eigen::Dynamic>& estimator() const { return rls_; }

 private:
  OnlineLpvArxOptions options_;
  Rls<Eigen::Dynamic> rls_;
  RingBuffer<double> u_history_;
  RingBuffer<double> y_history_;
  Eigen::VectorXd phi_;
  Eigen::VectorXd expanded_;
  std::int64_t k_ = -1;
  std::int64_t k_start_ = 0;
  std::int64_t last_bad_u_ = -1000000000;
  std::int64_t last_bad_y_ = -1000000000;
};

}  // namespace canalid::core
