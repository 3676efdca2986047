#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/experiment/experiment.h"
#include "core/experiment/experiment_design.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "core/reach/joint_experiments.h"
#include "core/reach/reach_controller.h"
#include "daemon/config/daemon_config.h"

namespace canalid::config {

using core::ExperimentDesign;
using core::ExperimentPlan;
using core::OnlineIntegratorDelayOptions;
using core::ReachControllerOptions;

/// The design of a mode = "design" experiment: core::DesignPrbsExperiment with the reach's nominal
/// inflow and expected delay, Ts of its PLC, amplitude_percent and duration_factor (the
/// explanation lines are for the daemon's log).
/// @throws std::invalid_argument for an explicit experiment or one whose reach does not resolve.
ExperimentDesign DesignExperiment(const DaemonConfig& config, const ExperimentConfig& experiment);

/// The ExperimentPlan of `experiment` (of a valid `config`), in samples of its reach's PLC,
/// Ts = poll_period_s * time_scale plant seconds:
///   design:   core::DesignPrbsExperiment(nominal_inflow_m3s, expected_delay_s, Ts,
///             amplitude_percent, duration_factor); the flow amplitude A_q becomes actuator units
///             as A_q / |actuator_gain_m3s_per_unit|, or, without a gain, as
///             amplitude_percent / 100 * |nominal_setpoint| (flow proportional to the setting);
///             clock, order and excitation length (periods * (2^order - 1) * clock) from the
///             design;
///   explicit: amplitude, clock = clock_period_s / Ts samples, order, periods as given;
///   settle_samples = ceil(settle_s / Ts), the level band of the reach, max_invalid_samples,
///   max_sample_gap_s = max_sample_gap_periods x the PLC's poll_period_s (wall s, as sample times).
/// @param nominal_setpoint the actuator's nominal (reach.nominal_setpoint, or its reading at
/// start).
/// @throws std::invalid_argument naming the experiment when the reach does not resolve, the
///   amplitude is not positive, or nominal +- amplitude leaves [setpoint_min, setpoint_max].
ExperimentPlan BuildExperimentPlan(const DaemonConfig& config, const ExperimentConfig& experiment,
                                   double nominal_setpoint);

/// The reach's online settings (core::OnlineModelSettings): Ts as above, the RLS method,
/// forgetting and initial covariance (when given), the delay range, the arx, frac-foptd and lpv
/// keys; the rest at their defaults.
/// @throws std::invalid_argument when the reach does not resolve.
core::OnlineModelSettings BuildOnlineModelSettings(const DaemonConfig& config,
                                                   const ReachConfig& reach);

/// Options of the reach's OnlineIntegratorDelayBank: core::OnlineModelOptionsFor the id kind and
/// BuildOnlineModelSettings (delays min_delay_s / Ts .. max_delay_s / Ts, rounded to the nearest
/// sample).
/// @throws std::invalid_argument when the reach does not resolve or an option is out of range.
OnlineIntegratorDelayOptions BuildOnlineIntegratorDelayOptions(const DaemonConfig& config,
                                                               const ReachConfig& reach);

/// Everything `reach` runs (the daemon live, `canalid replay` from a log): its channels in its
/// PLC's poll (`channel_index(name)`, which throws std::invalid_argument for a channel not polled),
/// sample time, online estimators (online_models: id, then the process models arx, frac-foptd,
/// lpv in the configured order, with the actuator_position and lpv_scheduling channels), batch
/// options (delay range of the bank, closed-loop setting),
/// nominal setpoint, and every [[experiment]] of the reach in file order (their plan factories
/// keep `config` alive).
/// @throws std::invalid_argument when the reach does not resolve.
ReachControllerOptions BuildReachControllerOptions(
    const std::shared_ptr<const DaemonConfig>& config, const ReachConfig& reach,
    const std::function<int(const std::string& channel)>& channel_index);

/// The joint experiments of `config` (its experiments with `with`) over the caller's reaches,
/// `reach_names` in the caller's order (indices into it): a joint whose leader the caller does
/// not run is left out, and so is a partner it does not run (`canalid replay --reach`).
std::vector<core::JointExperiment> BuildJointExperiments(
    const DaemonConfig& config, const std::vector<std::string>& reach_names);

}  // namespace canalid::config
