#include "daemon/canalid/report_online.h"

#include <algorithm>
#include <limits>

namespace canalid::cli {

void OnlineModelRecorder::OnConfig(const canalid::config_t& config,
                                   const drivers::LogEvent& event) {
  next_.OnConfig(config, event);
}

void OnlineModelRecorder::OnSample(const std::string& plc, const canalid::sample_t& sample,
                                   const drivers::LogEvent& event) {
  if (first_utime_ < 0) first_utime_ = sample.utime;
  next_.OnSample(plc, sample, event);
}

void OnlineModelRecorder::OnExperiment(const canalid::experiment_state_t& state,
                                       const drivers::LogEvent& event) {
  next_.OnExperiment(state, event);
}

void OnlineModelRecorder::OnModel(const canalid::model_snapshot_t& model,
                                  const drivers::LogEvent& event) {
  if (model.estimator == "rls-bank" || model.estimator == "rls") online_.push_back(model);
  next_.OnModel(model, event);
}

std::vector<OnlineTrajectory> OnlineModelRecorder::Trajectories(const std::string& reach) const {
  std::vector<OnlineTrajectory> out;
  std::vector<std::vector<const canalid::model_snapshot_t*>> rows;  // per trajectory
  for (const canalid::model_snapshot_t& m : online_) {
    if (m.reach != reach) continue;
    auto t = std::find_if(out.begin(), out.end(),
                          [&](const OnlineTrajectory& o) { return o.kind == m.model_kind; });
    if (t == out.end()) {
      OnlineTrajectory fresh;
      fresh.kind = m.model_kind;
      for (const std::string& name : m.param_names) {
        if (name.find("operating_point") == std::string::npos) fresh.names.push_back(name);
      }
      out.push_back(fresh);
      rows.emplace_back();
      t = out.end() - 1;
    }
    rows[static_cast<std::size_t>(t - out.begin())].push_back(&m);
  }
  const double t0 = static_cast<double>(std::max<std::int64_t>(first_utime_, 0));
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < out.size(); ++k) {
    OnlineTrajectory& t = out[k];
    const auto n = static_cast<Eigen::Index>(rows[k].size());
    const auto cols = static_cast<Eigen::Index>(t.names.size());
    t.time_s.resize(n);
    t.values = Eigen::MatrixXd::Constant(n, cols, kNan);
    t.std_devs = Eigen::MatrixXd::Constant(n, cols, kNan);
    for (Eigen::Index r = 0; r < n; ++r) {
      const canalid::model_snapshot_t& m = *rows[k][static_cast<std::size_t>(r)];
      t.time_s(r) = (static_cast<double>(m.utime) - t0) * 1e-6;
      for (Eigen::Index c = 0; c < cols; ++c) {
        for (std::size_t i = 0; i < m.param_names.size(); ++i) {
          if (m.param_names[i] != t.names[static_cast<std::size_t>(c)]) continue;
          t.values(r, c) = m.param_values[i];
          t.std_devs(r, c) = m.param_std_devs[i];
        }
      }
    }
  }
  return out;
}

}  // namespace canalid::cli
