#pragma once
#include <Eigen/Core>
#include <canalid/model_snapshot_t.hpp>

#include <string>
#include <vector>

#include "drivers/lcm/log_messages.h"

namespace canalid::cli {

/// One online model of a reach over a log, as the daemon published it on MODEL_<reach>.
struct OnlineTrajectory {
  std::string kind;                ///< an online kind: "id", "arx", "frac-foptd", "lpv", ...
  std::vector<std::string> names;  ///< its parameters (the constant operating points left out)
  Eigen::VectorXd time_s;          ///< of each snapshot, s since the log's first sample
  Eigen::MatrixXd values;          ///< one row per snapshot, one column per name
  Eigen::MatrixXd std_devs;        ///< 1 sigma, NaN where unknown
};

/// Forwards every message to `next` and keeps the online snapshots (estimator "rls-bank" or
/// "rls") of every reach, for OnlineTrajectories.
class OnlineModelRecorder final : public drivers::LogMessageVisitor {
 public:
  explicit OnlineModelRecorder(drivers::LogMessageVisitor& next) : next_(next) {}
  void OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) override;
  void OnSample(const std::string& plc, const canalid::sample_t& sample,
                const drivers::LogEvent& event) override;
  void OnExperiment(const canalid::experiment_state_t& state,
                    const drivers::LogEvent& event) override;
  void OnModel(const canalid::model_snapshot_t& model, const drivers::LogEvent& event) override;

  /// The trajectories of `reach`, one per kind in order of first appearance.
  std::vector<OnlineTrajectory> Trajectories(const std::string& reach) const;

 private:
  drivers::LogMessageVisitor& next_;
  std::vector<canalid::model_snapshot_t> online_;
  std::int64_t first_utime_ = -1;
};

}  // namespace canalid::cli
