#include "daemon/canalidd/results_feed.h"

#include <algorithm>
#include <limits>
#include <span>

#include "core/results/results_image.h"
#include "daemon/canalidd/clock.h"

namespace canalid::daemon {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> ReachNames(const DaemonPlan& plan) {
  std::vector<std::string> names;
  for (const ReachWiring& reach : plan.reaches) names.push_back(reach.runner.name);
  return names;
}

// The experiment's progress over its settle and excitation samples, and the wall seconds left.
core::ResultsExperiment Experiment(const core::ExperimentState& state,
                                   const core::ExperimentPlan* plan, double poll_period_s) {
  core::ResultsExperiment e;
  e.state = static_cast<std::uint8_t>(ExperimentStateCode(state.phase));
  e.abort_reason = static_cast<std::uint16_t>(state.abort_reason);
  e.setpoint = state.phase == core::ExperimentPhase::kIdle ? kNan : state.setpoint;
  if (plan == nullptr) return e;
  const auto total = static_cast<double>(plan->settle_samples + plan->excite_samples);
  double done = 0.0;
  switch (state.phase) {
    case core::ExperimentPhase::kSettling:
      done = static_cast<double>(state.samples_in_phase);
      break;
    case core::ExperimentPhase::kExciting:
      done = static_cast<double>(plan->settle_samples + state.samples_in_phase);
      break;
    case core::ExperimentPhase::kIdentifying:
    case core::ExperimentPhase::kDone:
      done = total;
      break;
    case core::ExperimentPhase::kIdle:
    case core::ExperimentPhase::kAborted:
      return e;
  }
  done = std::clamp(done, 0.0, total);
  e.progress = total > 0.0 ? done / total : 1.0;
  e.time_left_s = (total - done) * poll_period_s;
  return e;
}

}  // namespace

ResultsFeed::ResultsFeed(const DaemonPlan& plan) {
  drivers::ResultsServerOptions options;
  options.host = plan.results_host;
  options.port = std::to_string(plan.results_port);
  options.max_clients = plan.results_max_clients;
  server_ = std::make_unique<drivers::ResultsServer>(
      core::ResultsImage(ReachNames(plan), WallNowS()), options);
  for (const ReachWiring& reach : plan.reaches) {
    poll_period_s_.push_back(plan.plcs[static_cast<std::size_t>(reach.plc)].poller.period_s);
  }
}

void ResultsFeed::OnModel(const canalid::model_snapshot_t& m) {
  const auto n = static_cast<std::size_t>(std::max(0, m.num_params));
  core::ResultsModel model;
  model.kind = m.model_kind;
  model.estimator = m.estimator;
  model.time_s = static_cast<double>(m.utime) * 1e-6;
  model.samples_used = m.samples_used;
  model.names = std::span<const std::string>(m.param_names.data(), n);
  model.values = std::span<const double>(m.param_values.data(), n);
  model.std_devs = std::span<const double>(m.param_std_devs.data(), n);
  model.flags = m.flags;
  model.prediction_error_rms = m.prediction_error_rms;
  server_->Update(
      [&](core::ResultsImage& image) { image.SetModel(image.FindReach(m.reach), model); });
}

void ResultsFeed::OnReachPoll(int reach, const drivers::PollSample& sample,
                              const core::ReachReadings& readings) {
  core::ResultsPoll poll;
  poll.time_s = sample.time_s;
  poll.status = static_cast<std::uint16_t>(sample.status.kind);
  poll.exception_code = sample.status.kind == drivers::PlcErrorKind::kException
                            ? static_cast<std::uint16_t>(sample.status.exception_code)
                            : 0;
  poll.level_m = readings.level_valid ? readings.level_m : kNan;
  server_->Update([&](core::ResultsImage& image) { image.SetPoll(reach, poll); });
}

void ResultsFeed::OnReachState(int reach, const core::ReachController& controller) {
  const auto& plan = controller.pipeline().experiment_plan();
  const core::ResultsExperiment experiment =
      Experiment(controller.pipeline().experiment_state(), plan ? &*plan : nullptr,
                 poll_period_s_[static_cast<std::size_t>(reach)]);
  server_->Update([&](core::ResultsImage& image) { image.SetExperiment(reach, experiment); });
}

HealthReport ResultsFeed::Health() const {
  const drivers::ResultsServerCounters c = server_->counters();
  HealthReport report;
  report.component = "results";
  report.counters = {{"requests", c.requests},
                     {"refused_writes", c.refused_writes},
                     {"clients_accepted", c.clients_accepted},
                     {"clients_refused", c.clients_refused},
                     {"clients_dropped", c.clients_dropped}};
  report.gauges = {{"clients_connected", static_cast<double>(c.clients_connected)}};
  return report;
}

}  // namespace canalid::daemon
