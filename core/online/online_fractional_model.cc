// The "frac-foptd" kind of the online registry: OnlineFractionalBank (output error over a grid
// of alpha and T) from the actuator to the level, in deviations from the first sample; the
// level's operating point is that sample plus the fitted offset.
#include <cmath>
#include <limits>

#include "core/online/online_integrator_delay.h"
#include "core/online/online_model_kinds.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

class OnlineFractionalModel final : public ProcessOnlineModel {
 public:
  explicit OnlineFractionalModel(const OnlineModelOptions& options)
      : ProcessOnlineModel(options, {"gain", "time_constant_s", "alpha", "delay_s"}),
        options_(options.fractional),
        bank_(options.fractional) {}

  OnlineModelKind kind() const override { return OnlineModelKind::kFractionalFoptd; }

  bool Update(const OnlineSample& sample) override {
    const Deviations d = Deviate(sample);
    return bank_.Update(d.input, d.output);
  }

  void FillSnapshot(OnlineModelSnapshot& out) const override {
    const FractionalSnapshot s = bank_.Snapshot();
    SnapshotWriter w = Writer(out, "rls-bank", s.valid, s.health.updates);
    w.Put(s.gain, s.gain_std);
    w.Put(s.time_constant_s, s.time_constant_std_s);
    w.Put(s.alpha, kNan);
    w.Put(options_.delay_samples * options_.sample_time_s, kNan);
    PutOperatingPoint(w, s.offset, s.offset_std);
    int flags = 0;
    // The id kind's default thresholds (IntegratorDelayHealthOptions).
    if (s.information_min <
        IntegratorDelayHealthOptions{}.InformationMin(options_.rls.initial_covariance)) {
      flags |= kFlagLowExcitation;
    }
    // T at an end of the grid of characteristic times, or alpha at an end of a grid of several.
    if (s.at_grid_edge) flags |= kFlagOutOfBounds;
    w.Finish(s.health, s.condition_number, s.information_min, s.innovation_std, condition_max(),
             flags);
  }

  void Reset() override {
    bank_ = OnlineFractionalBank(options_);
    ResetOperatingPoint();
  }

 private:
  OnlineFractionalOptions options_;
  OnlineFractionalBank bank_;
};

}  // namespace

std::unique_ptr<OnlineModel> MakeOnlineFractionalModel(const OnlineModelOptions& options) {
  return std::make_unique<OnlineFractionalModel>(options);
}

}  // namespace canalid::core
