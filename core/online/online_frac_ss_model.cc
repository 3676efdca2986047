// The "frac-ss" kind of the online registry: OnlineCommensurate from the actuator to the level,
// in deviations from the operating point, for the configured q and delay.
#include <array>
#include <cmath>
#include <limits>

#include "core/online/online_commensurate.h"
#include "core/online/online_model_kinds.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// delay_s, alpha, a1..an, c1..c(n-1): the names of `canalid identify --model lpv --local frac-ss`.
std::vector<std::string> CommensurateNames(const OnlineCommensurateOptions& o) {
  std::vector<std::string> names{"delay_s", "alpha"};
  for (int i = 1; i <= o.order(); ++i) names.push_back("a" + std::to_string(i));
  for (int i = 1; i < o.order(); ++i) names.push_back("c" + std::to_string(i));
  return names;
}

class OnlineFracSsModel final : public ProcessOnlineModel {
 public:
  explicit OnlineFracSsModel(const OnlineModelOptions& options)
      : ProcessOnlineModel(options, CommensurateNames(options.frac_ss)),
        options_(options.frac_ss),
        estimator_(options.frac_ss) {}

  OnlineModelKind kind() const override { return OnlineModelKind::kFracSs; }

  bool Update(const OnlineSample& sample) override {
    const Deviations d = Deviate(sample);
    return estimator_.Update(d.input, d.output);
  }

  void FillSnapshot(OnlineModelSnapshot& out) const override {
    const Rls<Eigen::Dynamic>& rls = estimator_.estimator();
    const RlsHealth health = rls.health();
    // Valid once updated and a_n moved off 0 (the g regressors can be nonzero a few samples
    // before a_n's: c = g / a_n is undefined until then).
    const bool valid = health.updates > 0 && estimator_.a(options_.order()) != 0.0;
    SnapshotWriter w = Writer(out, "rls", valid, health.updates);
    w.Put(options_.delay_samples * sample_time_s(), kNan);
    w.Put(1.0 / options_.q, kNan);
    const int n = options_.order();
    for (int i = 1; i <= n; ++i) w.Put(estimator_.a(i), estimator_.a_std(i));
    estimator_.CStandardDeviations(c_std_);
    for (int i = 1; i < n; ++i) w.Put(estimator_.c(i), c_std_[static_cast<std::size_t>(i - 1)]);
    PutOperatingPoint(w);
    w.Finish(health, health.condition_estimate, kNan, std::sqrt(rls.innovation_variance()),
             condition_max());
  }

  void Reset() override {
    estimator_ = OnlineCommensurate(options_);
    ResetOperatingPoint();
  }

 private:
  OnlineCommensurateOptions options_;
  OnlineCommensurate estimator_;
  mutable std::array<double, 2 * kMaxOnlineCommensurateQ - 1> c_std_{};  // work of FillSnapshot
};

}  // namespace

std::unique_ptr<OnlineModel> MakeOnlineFracSsModel(const OnlineModelOptions& options) {
  return std::make_unique<OnlineFracSsModel>(options);
}

}  // namespace canalid::core
