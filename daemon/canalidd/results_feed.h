#pragma once
#include <canalid/model_snapshot_t.hpp>

#include <memory>
#include <string>
#include <vector>

#include "core/reach/reach_controller.h"
#include "daemon/canalidd/daemon_plan.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "drivers/modbus/plc_poller.h"
#include "drivers/modbus/results_server.h"

namespace canalid::daemon {

/// The daemon's side of the results register map (docs/results-register-map.md): owns the
/// ResultsServer (its own thread) and writes into its image what the daemon publishes: every
/// model message (LcmPublisher's model observer), after each poll the reach's comms status and
/// level, and whenever the reach's controller acted, its experiment's state.  Used on the daemon's
/// loop; each update holds the image's lock for a copy of a few words and does not allocate.
class ResultsFeed final {
 public:
  /// @throws std::runtime_error when the address cannot be bound.
  explicit ResultsFeed(const DaemonPlan& plan);

  void OnModel(const canalid::model_snapshot_t& model);
  /// Reach `reach` (index into plan.reaches) polled: its comms status and level.
  void OnReachPoll(int reach, const drivers::PollSample& sample,
                   const core::ReachReadings& readings);
  /// Reach `reach`'s experiment after its controller acted (phase, progress, time left, setpoint).
  void OnReachState(int reach, const core::ReachController& controller);

  int port() const { return server_->port(); }
  /// "results": requests, refused writes and connections.
  HealthReport Health() const;

 private:
  std::unique_ptr<drivers::ResultsServer> server_;
  std::vector<double> poll_period_s_;  ///< per reach: its PLC's poll period (wall s)
};

}  // namespace canalid::daemon
