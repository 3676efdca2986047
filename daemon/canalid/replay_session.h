#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/reach/joint_experiments.h"
#include "core/reach/reach_controller.h"
#include "daemon/canalid/recorded_config.h"
#include "drivers/lcm/log_messages.h"

namespace canalid::cli {

/// A model the replay produced: a batch identification at the end of an experiment, or a
/// snapshot of the online estimator bank.
struct ReplayModel {
  std::string reach;
  double log_time_s = 0.0;  ///< seconds since the first sample of the log (wall clock)
  bool batch = false;
  std::string kind = "id";  ///< the model kind ("id", "arx", "frac-foptd", "lpv")
  std::string estimator;    ///< as the daemon publishes it: "batch", "rls-bank", "rls"
  nlohmann::json json;      ///< the model JSON (docs/model-json.md) with "reach"
};

struct ReplaySessionOptions {
  std::optional<config::DaemonConfig> config;  ///< --config: instead of the one in the log
  std::string reach;                           ///< only this reach; empty: all
  std::optional<double> from_s, to_s;          ///< window, seconds since the first sample
  std::int64_t snapshot_every = 0;             ///< online snapshots every so many samples; 0: none
  std::string log_path;                        ///< for messages
};

/// Runs the daemon's per-reach code (core::ReachController, the same the daemon runs on every poll)
/// over the messages of a log: samples feed the reaches of their PLC, and experiment transitions
/// the samples cannot show (operator commands, write failures, link losses detected between
/// polls, stops) are taken from the recorded experiment messages, and estimator resets from the
/// daemon's "rls-bank-reset" model message, so a log of a live run gives the live models.  A daemon
/// restart or reload in the log (a PLC's sample sequence starting again) restarts the reaches with
/// the configuration in force, as the daemon did.
class ReplaySession final : public drivers::LogMessageVisitor {
 public:
  using ModelSink = std::function<void(const ReplayModel&)>;
  using WarningSink = std::function<void(const std::string&)>;

  ReplaySession(ReplaySessionOptions options, ModelSink on_model, WarningSink on_warning);
  ~ReplaySession() override;

  void OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) override;
  void OnSample(const std::string& plc, const canalid::sample_t& sample,
                const drivers::LogEvent& event) override;
  void OnExperiment(const canalid::experiment_state_t& state,
                    const drivers::LogEvent& event) override;
  void OnModel(const canalid::model_snapshot_t& model, const drivers::LogEvent& event) override;

  /// The final models of every replayed reach, in configuration order: the final snapshot of
  /// each online process model (arx, frac-foptd, lpv), the last batch process model of each kind
  /// (foptd, frac-foptd), then the reach's id model (the last batch model, else the online id
  /// snapshot).
  std::vector<ReplayModel> FinalModels() const;
  /// The replayed reaches that are configured with no model at all (online_models and
  /// batch_models empty: they only move their actuator in joint experiments).
  std::vector<std::string> ReachesWithoutModels() const;
  /// How many reaches the replay runs (the configuration's, or the one of --reach).
  std::size_t reach_count() const { return reaches_.size(); }
  /// The key of live_models(): "<model kind>/<estimator>" ("id/batch", "arx/rls-bank").
  static std::string LiveKey(const std::string& kind, const std::string& estimator) {
    return kind + "/" + estimator;
  }
  /// The last model each reach published live (from the log's MODEL_ messages), by reach and
  /// LiveKey.
  const std::map<std::string, std::map<std::string, canalid::model_snapshot_t>>& live_models()
      const {
    return live_models_;
  }
  std::int64_t samples_used() const { return samples_used_; }
  bool has_config() const { return config_.config() != nullptr; }

 private:
  struct Reach;
  struct Plc;

  void Restart();
  Plc* FindPlc(const std::string& name);
  void Step(Reach& reach, const core::ReachActions& actions, double log_time_s);
  /// The joint rules after `actions` of `reach` (core::JointExperiments::AfterPhaseChange).
  void Joint(const Reach& reach, const core::ReachActions& actions);
  ReplayModel OnlineIdModel(const Reach& reach, double log_time_s) const;
  // Every online model of the reach with a valid snapshot, id first, to `sink`.
  void OnlineModels(const Reach& reach, double log_time_s, bool with_id,
                    const std::function<void(ReplayModel)>& sink) const;

  ReplaySessionOptions options_;
  ModelSink on_model_;
  WarningSink on_warning_;
  RecordedConfig config_;
  std::vector<std::unique_ptr<Plc>> plcs_;
  std::vector<std::unique_ptr<Reach>> reaches_;
  core::JointExperiments joints_;  ///< over reaches_, as the daemon's over its reaches
  /// Each reach's controller (null until its runner is built), the view joints_ takes.
  std::vector<core::ReachController*> controllers_;
  std::map<std::string, std::map<std::string, canalid::model_snapshot_t>> live_models_;
  std::optional<std::int64_t> first_utime_;
  std::int64_t samples_used_ = 0;
  // Reach -> (reason, setpoint) of a start-up message on an interrupted experiment, for the
  // reach's next runner (core::RestartDecisionFromMessage).
  std::map<std::string, std::pair<std::string, double>> pending_restarts_;
};

}  // namespace canalid::cli
