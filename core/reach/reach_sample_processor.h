#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/experiment/experiment.h"
#include "core/integrator_delay/identify_idz.h"
#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "core/reach/process_batch.h"

namespace canalid::core {

/// One poll's values for one reach, already scaled to engineering units.
struct ReachSample {
  double q_in_m3s = 0.0;
  double q_out_m3s = 0.0;
  double level_m = 0.0;
  bool q_in_valid = false;
  bool q_out_valid = false;
  bool level_valid = false;
  bool link_ok = true;  ///< the PLC answered this poll
  /// The process models' input (the actuator's position or setpoint) and lpv's scheduling
  /// variable; NaN: invalid or not read.
  double input = std::numeric_limits<double>::quiet_NaN();
  double scheduling = std::numeric_limits<double>::quiet_NaN();
  /// When the poll was taken (s; the daemon's wall clock, replay's log time; NaN: unknown).
  /// A running experiment aborts on a gap (ExperimentPlan::max_sample_gap_s).
  double time_s = std::numeric_limits<double>::quiet_NaN();
};

struct ReachSampleProcessorOptions {
  double sample_time_s = 1.0;  ///< plant seconds between samples
  /// The online id kind's options (sample_time_s is overwritten with the one above), and the
  /// bounds every id model of the reach must satisfy (model_bounds()), enabled or not.
  OnlineIntegratorDelayOptions online_id;
  bool online_id_enabled = true;
  /// The other online kinds (arx, frac-foptd, lpv: the actuator to the level), each at most once.
  std::vector<OnlineModelOptions> process_models;
  std::optional<ExperimentPlan> experiment;    ///< none: this reach never excites its actuator
  IntegratorDelayIdentificationOptions batch;  ///< identification at the end of each experiment
  bool batch_id = true;  ///< the integrator-delay model is identified at the end of experiments
  /// The IDZ model identified at the end of experiments too (from the same record as the ID
  /// model, with its own p22 prior), when set; its delay range is the ID bank's.
  std::optional<IdzIdentificationOptions> batch_idz;
  /// The process models identified at the end of experiments too, from the recorded input (the
  /// actuator, as the process models' online input) and level, delays up to the bank's largest.
  std::vector<ProcessBatchKind> batch_process_models;
  /// Their settings: the arx orders (the delay range is the online id bank's).
  ProcessBatchOptions batch_process;
};

/// What the daemon must do after a sample or a command.
struct ReachActions {
  std::optional<double> write_setpoint;  ///< to the reach's actuator, now
  bool restore_nominal = false;
  bool experiment_phase_changed = false;
  bool experiment_record_complete = false;  ///< call IdentifyRecord()
  bool online_updated = false;              ///< some online estimate moved: publish it
  /// Bit i: online_models()[i] moved on this sample.
  std::uint32_t online_models_updated = 0;
};

/// Everything one reach does per sample, as plain data in and out (no I/O, no clocks): the online
/// ID estimator bank, the experiment state machine with its safety rules, and the record of the
/// running experiment (preallocated for the plan's length: nothing is allocated per sample).
/// Deterministic: the same samples and commands give the same actions and estimates, which is
/// what lets `canalid replay` reproduce a live run from its log.
class ReachSampleProcessor final {
 public:
  /// @throws std::invalid_argument on bad options.
  explicit ReachSampleProcessor(const ReachSampleProcessorOptions& options);

  ReachActions OnSample(const ReachSample& sample);
  /// Starts at the time of the last sample: the next one must follow within the plan's gap bound.
  ReachActions StartExperiment();
  ReachActions StopExperiment();
  /// Its joint experiment fails (core/reach/joint_experiments.h): aborts a running experiment
  /// with kJointStop, restoring the nominal.
  ReachActions StopJointExperiment();
  /// Its joint experiment's leader completed its excitation: a running experiment ends done
  /// (kJointEnd), restoring the nominal, without identification.
  ReachActions EndJointExperiment();
  /// The PLC link is down and no samples come (the poller is reconnecting): abort if running.
  /// Nothing else changes (no estimator update, no sample counted).
  ReachActions OnLinkLost();
  /// A setpoint write of this reach failed: abort if exciting.
  ReachActions OnWriteFailed();
  /// The guard that must precede an excitation write could not be persisted: abort if running.
  ReachActions OnGuardNotPersisted();
  /// Installs (or replaces) the experiment plan, e.g. once the actuator's nominal setpoint has
  /// been read from the PLC.  Allocates the record for the plan's length (not per sample).
  /// Returns false, changing nothing, while an experiment runs.
  /// @throws std::invalid_argument if the plan is invalid.
  bool SetExperimentPlan(const ExperimentPlan& plan);

  /// Restarts the online estimators from their initial state (operator command, detected change).
  void ResetOnlineEstimator();

  /// Batch identification of the completed record: the ID model pipeline (when batch_id; else
  /// no result), the IDZ model (when batch_idz, idz_result()) and every batch process model
  /// (process_batch_results()).  Then the experiment ends done or aborted
  /// (kIdentificationFailed): with batch_id by the ID model (inside the bounds of the reach's
  /// delay bank, IntegratorDelayBoundsProblem; the result, if any, is still returned for the
  /// operator to see, and identification_problem() says why it is not the reach's model), else
  /// done when the IDZ model (within the same bounds) or some process model fitted, and done with
  /// no model when no batch kind is configured (a reach that only moves its actuator in joint
  /// experiments).
  /// @pre a record is complete.
  std::optional<IntegratorDelayIdentification> IdentifyRecord(ReachActions* actions);
  /// Why the last IdentifyRecord gave no usable model (empty when it did).
  const std::string& identification_problem() const { return identification_problem_; }
  /// The IDZ model of the last IdentifyRecord (none when batch_idz is unset or the fit failed,
  /// idz_problem() then says why), and why it is not the reach's model (empty when it is).
  const std::optional<IdzIdentification>& idz_result() const { return idz_result_; }
  const std::string& idz_problem() const { return idz_problem_; }
  /// The process models of the last IdentifyRecord, in batch_process_models' order.
  const std::vector<ProcessBatchResult>& process_batch_results() const { return process_results_; }
  /// The bounds a model of this reach must satisfy (the online bank's delay range and Ts).
  const OnlineIntegratorDelayOptions& model_bounds() const { return options_.online_id; }

  const ReachSampleProcessorOptions& options() const { return options_; }
  const ExperimentState& experiment_state() const { return experiment_state_; }
  const std::optional<ExperimentPlan>& experiment_plan() const { return options_.experiment; }
  /// The id kind's bank (nullptr when the reach does not run it).
  const OnlineIntegratorDelayBank* online_id() const { return online_id_; }
  /// Every online estimator of the reach: id first when enabled, then process_models in order.
  const std::vector<std::unique_ptr<OnlineModel>>& online_models() const { return online_models_; }
  Eigen::Index recorded_samples() const { return recorded_; }
  std::int64_t samples() const { return samples_; }

 private:
  ReachActions Apply(const ExperimentEvent& event);

  ReachSampleProcessorOptions options_;
  std::vector<std::unique_ptr<OnlineModel>> online_models_;
  const OnlineIntegratorDelayBank* online_id_ = nullptr;  // inside online_models_
  ExperimentState experiment_state_;
  Eigen::VectorXd record_q_in_, record_q_out_, record_level_, record_input_;
  std::vector<ProcessBatchResult> process_results_;
  std::optional<IdzIdentification> idz_result_;
  std::string idz_problem_;
  // The last valid input and level, and those of the sample before the record (its rest point).
  double previous_input_ = std::numeric_limits<double>::quiet_NaN();
  double previous_level_ = std::numeric_limits<double>::quiet_NaN();
  double rest_input_ = std::numeric_limits<double>::quiet_NaN();
  double rest_level_ = std::numeric_limits<double>::quiet_NaN();
  Eigen::Index recorded_ = 0;
  bool record_this_sample_ = false;
  std::int64_t samples_ = 0;
  double last_time_s_ = std::numeric_limits<double>::quiet_NaN();  // of the last sample
  std::string identification_problem_;
};

}  // namespace canalid::core
