// The "arx" kind of the online registry: OnlineArxBank from the actuator to the level, in
// deviations from the operating point.
#include <cmath>
#include <limits>

#include "core/online/online_model_kinds.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> ArxNames(const OnlineArxOptions& o) {
  std::vector<std::string> names{"delay_s"};
  for (int j = 1; j <= o.na; ++j) names.push_back("a" + std::to_string(j));
  for (int j = 1; j <= o.nb; ++j) names.push_back("b" + std::to_string(j));
  return names;
}

class OnlineArxModel final : public ProcessOnlineModel {
 public:
  explicit OnlineArxModel(const OnlineModelOptions& options)
      : ProcessOnlineModel(options, ArxNames(options.arx)),
        options_(options.arx),
        bank_(options.arx) {}

  OnlineModelKind kind() const override { return OnlineModelKind::kArx; }

  bool Update(const OnlineSample& sample) override {
    const Deviations d = Deviate(sample);
    return bank_.Update(d.input, d.output);
  }

  void FillSnapshot(OnlineModelSnapshot& out) const override {
    const ArxSnapshot s = bank_.Snapshot();
    SnapshotWriter w = Writer(out, "rls-bank", s.valid, s.health.updates);
    // Before the first estimate the bank's snapshot is empty: NaN in every coefficient's place.
    w.Put(s.valid ? s.delay_samples * sample_time_s() : kNan, kNan);
    for (Eigen::Index j = 0; j < options_.na; ++j) {
      w.Put(s.valid ? s.a(j) : kNan, s.valid ? s.a_std(j) : kNan);
    }
    for (Eigen::Index j = 0; j < options_.nb; ++j) {
      w.Put(s.valid ? s.b(j) : kNan, s.valid ? s.b_std(j) : kNan);
    }
    PutOperatingPoint(w);
    // At an edge of the delay bank the true delay may lie outside it.
    const bool bank = options_.max_delay_samples > options_.min_delay_samples;
    const bool at_edge =
        bank && (s.delay_samples == options_.max_delay_samples ||
                 (s.delay_samples == options_.min_delay_samples && s.delay_samples > 0));
    w.Finish(s.health, s.health.condition_estimate, kNan, s.innovation_std, condition_max(),
             at_edge ? kFlagOutOfBounds : 0);
  }

  void Reset() override {
    bank_ = OnlineArxBank(options_);
    ResetOperatingPoint();
  }

 private:
  OnlineArxOptions options_;
  OnlineArxBank bank_;
};

}  // namespace

std::unique_ptr<OnlineModel> MakeOnlineArxModel(const OnlineModelOptions& options) {
  return std::make_unique<OnlineArxModel>(options);
}

}  // namespace canalid::core
