#pragma once
#include <array>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "daemon/canalid/recorded_config.h"
#include "drivers/lcm/log_messages.h"

namespace canalid::cli {

/// Writes the samples of each reach of a log to `<dir>/<reach>.csv` and the published models to
/// `<dir>/models.csv`, as the log is read (nothing is held in memory but one row):
/// - `<reach>.csv`: time_s (plant seconds since the reach's first exported sample, from the poll
///   sequence x poll_period_s x time_scale, so dropped polls leave gaps and a daemon restart
///   carries on), the reach's inflow, outflow, level and actuator channels under their
///   configured names (engineering SI units; NaN where the sample was not valid), wall_time_s
///   (Unix seconds of the poll);
/// - `models.csv`: wall_time_s, reach, model_kind, estimator, samples_used, one column per
///   parameter name met in the log (`model_parameters`, found by a first pass) and its _std,
///   trace_p, condition_number, excitation, prediction_error_rms, flags.
class LogExporter final : public drivers::LogMessageVisitor {
 public:
  /// @throws InputError when a file cannot be created.
  LogExporter(std::string dir, std::optional<config::DaemonConfig> config, std::string reach,
              std::vector<std::string> model_parameters, std::string log_path);
  ~LogExporter() override;

  void OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) override;
  void OnSample(const std::string& plc, const canalid::sample_t& sample,
                const drivers::LogEvent& event) override;
  void OnModel(const canalid::model_snapshot_t& model, const drivers::LogEvent& event) override;

  /// Closes every file.  @throws InputError when a write failed.
  void Finish();
  bool has_config() const { return config_.config() != nullptr; }
  /// Rows written per file name.
  const std::map<std::string, std::int64_t>& rows() const { return rows_; }
  /// The channels (inflow, outflow, level, actuator) of every reach written, by reach.
  const std::map<std::string, std::array<std::string, 4>>& reach_channels() const {
    return reach_channels_;
  }

 private:
  struct ReachFile;
  std::FILE* Open(const std::string& name);

  std::string dir_;
  RecordedConfig config_;
  std::string reach_filter_;
  std::vector<std::string> model_parameters_;
  std::string log_path_;
  std::vector<std::unique_ptr<ReachFile>> reaches_;
  std::FILE* models_ = nullptr;
  std::vector<std::FILE*> files_;
  std::map<std::string, std::int64_t> rows_;
  std::map<std::string, std::array<std::string, 4>> reach_channels_;
};

/// The parameter names of the MODEL_ messages of a log, in order of first appearance (the first
/// pass of an export).
class ModelParameterCollector final : public drivers::LogMessageVisitor {
 public:
  void OnModel(const canalid::model_snapshot_t& model, const drivers::LogEvent& event) override;
  std::vector<std::string> names;

 private:
  std::set<std::string> seen_;
};

}  // namespace canalid::cli
