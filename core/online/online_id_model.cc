// The "id" and "idz" kinds of the online registry: OnlineIntegratorDelayBank on the flows and the
// level (idz: with the wave front and the outflow's direct gain held at its prior).
#include <limits>

#include "core/online/online_model_kinds.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

class OnlineIntegratorDelayModel final : public OnlineModel {
 public:
  explicit OnlineIntegratorDelayModel(const OnlineModelOptions& options)
      : kind_(options.kind), options_(options.id), bank_(options.id) {
    if (options_.wave_front_term) names_.emplace_back("p21_s_per_m2");
    if (kind_ == OnlineModelKind::kIdz) names_.emplace_back("p22_s_per_m2");
  }

  OnlineModelKind kind() const override { return kind_; }

  bool Update(const OnlineSample& s) override {
    return bank_.Update(s.q_in_m3s, s.q_out_m3s, s.level_m);
  }

  void FillSnapshot(OnlineModelSnapshot& out) const override {
    const IntegratorDelaySnapshot s = bank_.Snapshot();
    SnapshotWriter w(out, kind(), "rls-bank", s.valid, s.health.updates, names_);
    w.Put(s.delay_s, kNan);
    w.Put(s.area_m2, s.area_std_m2);
    w.Put(s.b, s.b_std);
    w.Put(s.c_m, s.c_std_m);
    w.Put(s.d_m, s.d_std_m);
    if (options_.wave_front_term) w.Put(s.wave_front_gain_s_per_m2, kNan);
    if (kind_ == OnlineModelKind::kIdz) w.Put(options_.outflow_direct_gain_s_per_m2, kNan);
    w.Finish(s.health, s.condition_number, s.information_min, s.innovation_std_m,
             std::numeric_limits<double>::infinity());
    // The bank's own flags (IntegratorDelaySnapshotFlags: its thresholds and bounds).
    out.flags = s.flags;
  }

  void Reset() override { bank_ = OnlineIntegratorDelayBank(options_); }

  const OnlineIntegratorDelayBank* integrator_delay_bank() const override { return &bank_; }

 private:
  OnlineModelKind kind_;
  OnlineIntegratorDelayOptions options_;
  OnlineIntegratorDelayBank bank_;
  std::vector<std::string> names_{"delay_s", "area_m2", "b", "offset_m", "drift_m_per_sample"};
};

}  // namespace

std::unique_ptr<OnlineModel> MakeOnlineIntegratorDelayModel(const OnlineModelOptions& options) {
  return std::make_unique<OnlineIntegratorDelayModel>(options);
}

}  // namespace canalid::core
