#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/reach/reach_sample_processor.h"
#include "daemon/canalidd/command_dispatch.h"
#include "daemon/canalidd/daemon_plan.h"
#include "daemon/canalidd/daemon_runtime.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/persistence_worker.h"
#include "daemon/canalidd/results_feed.h"
#include "daemon/canalidd/signal_watch.h"
#include "daemon/canalidd/state_store.h"
#include "drivers/auth/command_auth.h"
#include "drivers/lcm/bus.h"
#include "drivers/lcm/bus_watch.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// How Run() ended.
enum class DaemonExit { kStopped, kReload, kFailed };

/// The daemon's runtime: one Asio loop on the calling thread, one poller thread per PLC, one
/// core::ReachController per reach.  Decisions on plant data are the controllers' (core); this
/// class moves samples, actions and messages between them, the PLCs and the bus, and wires the
/// parts that do one job each: SignalWatch, BusWatch, Heartbeat, CommandDispatch, restore_safety.h,
/// model_persistence.h with its PersistenceWorker, health_report.h.
///
/// Persistence: an identified model is saved on the PersistenceWorker's thread, never on the
/// sample path; Run() saves every queued model before it returns.
///
/// Safety (the rules are core::ReachController's and core::DecideStop's, tested in process; the
/// daemon carries out their actions): every restore of a nominal setpoint stays pending until the
/// PLC confirms a write of the nominal queued since the restore began (a write refused while the
/// link is down, or shortened by the rate limit, is asked again on the next sample with the link
/// up); the next experiment's excitation write supersedes it.  No excitation write goes out
/// before the reach's experiment guard (core/experiment/experiment_guard.h) is durably in the
/// state directory; the guard is removed once the PLC confirms the nominal at the experiment's
/// end.  At start, a guard left by a crash is decided on by core::DecideRestart: its nominal is
/// restored first, before any experiment. SIGTERM/SIGINT stop the experiments, wait (at most
/// `stop_timeout_s`) for the nominal setpoints to be written, then stop.  SIGHUP asks `reload` for
/// a new plan: when it returns one, Run() stops safely and returns kReload (the caller builds a new
/// Daemon); when it returns none (invalid configuration), the daemon carries on.
class Daemon final {
 public:
  using PortFactory = std::function<std::unique_ptr<drivers::PlcPort>(const PlcWiring&)>;
  using ReloadFunction = std::function<std::optional<DaemonPlan>()>;

  /// @throws std::invalid_argument / std::runtime_error on a plan the drivers refuse (start-up).
  /// `bus` outlives the daemon; it is kept across reloads so an LCM log being written is not
  /// reopened (and truncated) by the next daemon.
  Daemon(DaemonPlan plan, drivers::Bus& bus, PortFactory make_port, ReloadFunction reload);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  DaemonExit Run();
  /// The plan returned by `reload` when Run() returned kReload.
  std::optional<DaemonPlan> TakeReloadedPlan() { return std::move(reloaded_plan_); }

  /// Production port factory: libmodbus TCP or RTU from the wiring.
  static std::unique_ptr<drivers::PlcPort> MakeModbusPort(const PlcWiring& wiring);

  double stop_timeout_s = 5.0;

 private:
  void Drain(int plc);
  void OnPoll(int plc, const drivers::PollSample& sample);
  void OnWriteResult(int plc, const drivers::WriteResult& result);
  void Handle(ReachRuntime& reach, const core::ReachActions& actions, double time_s);
  /// Publishes, logs and persists the process models of the reach's last identification.
  /// The reach's IDZ model of the last IdentifyRecord: logged, published (flagged when out of
  /// bounds) and persisted like the process models.
  void ReportIdzModel(const ReachRuntime& reach, double time_s);
  /// One end-of-experiment model other than id: published with estimator "batch", logged, and
  /// persisted unless `problem` says why it is not the reach's model.
  void PublishBatchModel(const ReachRuntime& reach, const std::string& kind,
                         const nlohmann::json& json, const std::string& problem, double time_s,
                         std::int32_t flags = 0);
  void ReportProcessModels(const ReachRuntime& reach, double time_s);
  /// Publishes the snapshot of every online model the sample moved.
  void PublishOnlineModels(ReachRuntime& reach, const core::ReachActions& actions, double time_s);
  void RequestSetpoint(ReachRuntime& reach, double value);
  void StartHealthTimer();
  void PublishHealth();
  // SIGHUP: asks `reload` for a new plan; true when the daemon stops to reload.
  bool Reload();
  // The state directory: the store, the persisted models resumed, the save thread started.
  void LoadState();
  // Queues the reach's model for the save thread (never blocks on the disk).
  void SaveModel(const ReachRuntime& reach, const core::IntegratorDelayIdentification& result);
  // A command the dispatch let through, routed to the reach it names.
  void OnCommand(const drivers::AcceptedCommand& command);
  void BeginStop(DaemonExit exit);
  void FinishStopWhenSafe();
  StateStore* store() { return store_ ? &*store_ : nullptr; }
  std::string Status() const;

  DaemonPlan plan_;
  drivers::Bus& bus_;
  PortFactory make_port_;
  ReloadFunction reload_;
  boost::asio::io_context io_;
  SignalWatch signals_;
  drivers::BusWatch bus_watch_;
  boost::asio::steady_timer health_timer_;
  boost::asio::steady_timer stop_timer_;
  LcmPublisher publisher_;
  CommandDispatch commands_;
  std::vector<std::unique_ptr<PlcRuntime>> plcs_;
  std::vector<std::unique_ptr<ReachRuntime>> reaches_;
  std::vector<core::ReachController*> controllers_;  ///< each reach's, for joints_
  core::JointExperiments joints_;
  std::optional<DaemonPlan> reloaded_plan_;
  std::optional<StateStore> store_;
  std::unique_ptr<PersistenceWorker> model_saver_;  ///< with a state directory
  std::unique_ptr<ResultsFeed> results_;            ///< with [results] listen
  core::OnlineModelSnapshot snapshot_;              ///< reused for every online model's publication
  DaemonExit exit_ = DaemonExit::kStopped;
  bool stopping_ = false;
  bool ready_ = false;
  double start_steady_s_ = 0.0;
  double stop_deadline_s_ = 0.0;
  double last_watchdog_s_ = 0.0;
  double watchdog_period_s_ = 0.0;  ///< WatchdogSec from systemd, read once at start
};

}  // namespace canalid::daemon
