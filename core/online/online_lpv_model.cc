// The "lpv" kind of the online registry: OnlineLpvArx from the actuator to the level, in
// deviations from the operating point, scheduled on the raw scheduling variable.
#include <cmath>
#include <limits>

#include "core/online/online_model_kinds.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// theta's order (OnlineLpvArx): a1_0, a1_1, a1_2, a2_0, ..., b1_0, b1_1, b1_2, ...; p_m is the
// coefficient of s^m.
std::vector<std::string> LpvNames(const OnlineLpvArxOptions& o) {
  std::vector<std::string> names{"delay_s"};
  for (const char* coefficient : {"a", "b"}) {
    const int count = coefficient[0] == 'a' ? o.na : o.nb;
    for (int j = 1; j <= count; ++j) {
      for (int m = 0; m < 3; ++m) {
        names.push_back(coefficient + std::to_string(j) + "_" + std::to_string(m));
      }
    }
  }
  return names;
}

class OnlineLpvModel final : public ProcessOnlineModel {
 public:
  explicit OnlineLpvModel(const OnlineModelOptions& options)
      : ProcessOnlineModel(options, LpvNames(options.lpv)),
        options_(options.lpv),
        estimator_(options.lpv) {}

  OnlineModelKind kind() const override { return OnlineModelKind::kLpvArx; }

  bool Update(const OnlineSample& sample) override {
    const Deviations d = Deviate(sample);
    return estimator_.Update(d.input, d.output, sample.scheduling);
  }

  void FillSnapshot(OnlineModelSnapshot& out) const override {
    const Rls<Eigen::Dynamic>& rls = estimator_.estimator();
    const RlsHealth health = rls.health();
    SnapshotWriter w = Writer(out, "rls", health.updates > 0, health.updates);
    w.Put(options_.delay_samples * sample_time_s(), kNan);
    for (int j = 0; j < rls.num_params(); ++j) w.Put(rls.theta()(j), rls.StandardDeviation(j));
    PutOperatingPoint(w);
    w.Finish(health, health.condition_estimate, kNan, std::sqrt(rls.innovation_variance()),
             condition_max());
  }

  void Reset() override {
    estimator_ = OnlineLpvArx(options_);
    ResetOperatingPoint();
  }

 private:
  OnlineLpvArxOptions options_;
  OnlineLpvArx estimator_;
};

}  // namespace

std::unique_ptr<OnlineModel> MakeOnlineLpvModel(const OnlineModelOptions& options) {
  return std::make_unique<OnlineLpvModel>(options);
}

}  // namespace canalid::core
