#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/reach/reach_controller.h"
#include "core/reach/reach_sample_processor.h"
#include "daemon/canalidd/daemon_plan.h"
#include "daemon/canalidd/heartbeat.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// What the daemon keeps of one running PLC (owned by Daemon, used on its Asio loop).
struct PlcRuntime {
  explicit PlcRuntime(const PlcWiring& w) : wiring(w) {}
  const PlcWiring& wiring;
  std::unique_ptr<drivers::PlcPoller> poller;
  std::vector<std::string> channel_names;
  std::atomic<bool> drain_pending{false};  ///< a Drain is posted (set by the poller thread)
  std::unique_ptr<Heartbeat> heartbeat;
  std::vector<int> reaches;  ///< indices of the reaches read from this PLC
};

/// What the daemon keeps of one running reach (owned by Daemon, used on its Asio loop).
struct ReachRuntime {
  explicit ReachRuntime(const ReachWiring& w)
      : wiring(w), runner(w.runner), published_at(runner.pipeline().online_models().size(), -1) {}
  const ReachWiring& wiring;
  int index = 0;  ///< in the plan's reaches
  core::ReachController runner;
  double last_time_s = 0.0;
  /// Per online model (ReachSampleProcessor::online_models()): the sample it was last published
  /// at, -1 before its first publication (model_publish_every).
  std::vector<std::int64_t> published_at;
  const std::string& name() const { return runner.name(); }
  const core::ReachSampleProcessor& pipeline() const { return runner.pipeline(); }
};

/// The name of the reach's actuator channel in its PLC's poll.  @pre the reach has an actuator.
inline const std::string& ActuatorName(const std::vector<std::unique_ptr<PlcRuntime>>& plcs,
                                       const ReachRuntime& reach) {
  return plcs[static_cast<std::size_t>(reach.wiring.plc)]
      ->channel_names[static_cast<std::size_t>(reach.wiring.runner.channels.actuator)];
}

}  // namespace canalid::daemon
