#pragma once
#include <canalid/config_t.hpp>
#include <canalid/experiment_state_t.hpp>
#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/experiment/experiment.h"
#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "drivers/lcm/bus.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// Counters and gauges of one component, for canalid.health_t.
struct HealthReport {
  std::string component;
  std::vector<std::pair<std::string, int64_t>> counters;
  std::vector<std::pair<std::string, double>> gauges;
};

/// Publishes the daemon's messages on `<prefix>SAMPLE_<plc>`, `<prefix>MODEL_<reach>`,
/// `<prefix>EXPERIMENT_<reach>`, `<prefix>HEALTH` and `<prefix>CONFIG` (docs/lcm-channels.md).
/// Message objects and encode buffers are kept and reused, so steady publishing does not
/// allocate once the first message of each kind has been sent.  Counts refused publications.
class LcmPublisher final {
 public:
  LcmPublisher(drivers::Bus& bus, std::string prefix);

  void PublishSample(const std::string& plc, const std::vector<std::string>& channel_names,
                     const drivers::PollSample& sample);
  /// An online estimator's snapshot (model_kind its kind's name, estimator the snapshot's, or
  /// `estimator` when given: "rls-bank-reset" marks an operator's reset in the record).
  void PublishOnlineModel(const std::string& reach, const core::OnlineModelSnapshot& snapshot,
                          double time_s, std::string_view estimator = {});
  /// `out_of_bounds`: the model failed the reach's bounds (FLAG_OUT_OF_BOUNDS; not persisted).
  void PublishBatchId(const std::string& reach, const core::IntegratorDelayIdentification& result,
                      double time_s, std::int64_t samples, bool out_of_bounds);
  /// A model given as its model JSON (the numeric keys delay_s, area_m2, b, p21_s_per_m2,
  /// offset_m, gain, time_constant_s, alpha; prediction_error_rms from metrics.rmse): one from
  /// the state directory (estimator "persisted"), or an end-of-experiment process model
  /// ("batch", with the samples it used and its flags).
  void PublishModelJson(const std::string& reach, const nlohmann::json& model, double time_s,
                        const char* estimator = "persisted", std::int64_t samples = 0,
                        std::int32_t flags = 0);
  /// The state of `reach`'s experiment named `experiment` (the controller's experiment_name()).
  void PublishExperiment(const std::string& reach, const std::string& experiment,
                         const core::ExperimentState& state, const core::ExperimentPlan& plan,
                         const std::string& actuator, double time_s);
  /// The start-up decision on an interrupted experiment (state aborted, `reason` one of
  /// core::kRestartRestoreReason / kRestartRefusedReason and details, `setpoint` the value restored
  /// first, NaN when none).
  void PublishRestart(const std::string& reach, const std::string& actuator, double setpoint,
                      const std::string& reason, double time_s);
  void PublishHealth(const HealthReport& report, double uptime_s, double time_s);
  void PublishConfig(const std::string& path, const std::string& text, double time_s);

  /// Called with every model message after it is sent (also when the bus refused it): the
  /// results register map shows what was published.
  void SetModelObserver(std::function<void(const canalid::model_snapshot_t&)> observer) {
    model_observer_ = std::move(observer);
  }

  std::int64_t failures() const { return failures_; }
  const std::string& prefix() const { return prefix_; }

 private:
  void SendModel(const std::string& reach);
  template <class Message>
  void Send(const std::string& channel, const Message& message);
  const std::string& Channel(std::map<std::string, std::string, std::less<>>& cache,
                             const char* kind, const std::string& name);

  drivers::Bus& bus_;
  std::string prefix_;
  std::vector<std::uint8_t> buffer_;
  std::map<std::string, std::string, std::less<>> sample_channels_, model_channels_,
      experiment_channels_;
  canalid::sample_t sample_;
  canalid::model_snapshot_t model_;
  canalid::experiment_state_t experiment_;
  canalid::health_t health_;
  std::int64_t failures_ = 0;
  std::function<void(const canalid::model_snapshot_t&)> model_observer_;
};

/// experiment_state_t.STATE_* of a phase.
int8_t ExperimentStateCode(core::ExperimentPhase phase);

/// Microseconds since the epoch from seconds.
inline std::int64_t ToUtime(double time_s) { return static_cast<std::int64_t>(time_s * 1e6); }

}  // namespace canalid::daemon
