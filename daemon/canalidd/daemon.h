#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (DESIGN.md)

#include <array>
#include <boost/asio.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/command_auth.h"
#include "core/reach_pipeline.h"
#include "daemon/canalidd/daemon_plan.h"
#include "daemon/canalidd/lcm_publisher.h"
#include "daemon/canalidd/state_store.h"
#include "drivers/lcm/bus.h"
#include "drivers/lcm/command_receiver.h"
#include "drivers/lcm/lcm_bus.h"
#include "drivers/modbus/plc_poller.h"

namespace canalid::daemon {

/// How Run() ended.
enum class DaemonExit { kStopped, kReload, kFailed };

/// The daemon's runtime: one Asio loop on the calling thread, one poller thread per PLC, one
/// ReachPipeline per reach.  Decisions on plant data are the pipelines' (core); this class moves
/// samples, actions and messages between them, the PLCs and the bus.
///
/// Safety: every restore of a nominal setpoint stays pending until the PLC confirms the nominal
/// value was written (a write refused while the link is down, or shortened by the rate limit, is
/// asked again on the next sample).  No excitation write goes out before the reach's experiment
/// guard (core/experiment_guard.h) is durably in the state directory; the guard is removed once
/// the PLC confirms the nominal at the experiment's end.  At start, a guard left by a crash is
/// decided on by core::DecideRestart: its nominal is restored first, before any experiment.
/// SIGTERM/SIGINT stop the experiments, wait (at most `stop_timeout_s`) for the nominal setpoints
/// to be written, then stop.  SIGHUP asks `reload` for a new plan: when it returns one, Run() stops
/// safely and returns kReload (the caller builds a new Daemon); when it returns none (invalid
/// configuration), the daemon carries on.
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
  struct Reach;
  struct Plc;

  void StartPollers();
  void Drain(int plc);
  void OnPoll(int plc, const drivers::PollSample& sample);
  void OnWriteResult(int plc, const drivers::WriteResult& result);
  void Handle(Reach& reach, const core::ReachActions& actions, double time_s);
  void RequestSetpoint(Reach& reach, double value);
  void StartHeartbeat(int plc);
  void StartHealthTimer();
  void StartBusWatch();
  void WatchBus();
  void WaitForBus();
  // The LCM connection is gone (tcpq hub lost): counts it and retries with a doubling backoff.
  void OnBusLost(const std::string& why);
  // True when descriptors a and b name the same open socket (file).
  static bool SameSocket(int a, int b);
  void StartSignals();
  void PublishHealth();
  void LoadState();
  // Applies core::DecideRestart to each reach's guard (before the pollers start).
  void ResumeInterruptedExperiments();
  // Writes the reach's experiment guard; false (logged) when it is not durably on disk.
  bool PersistGuard(Reach& reach);
  // The PLC confirmed the reach's pending restore.
  void OnRestoreConfirmed(Reach& reach);
  void SaveModel(const Reach& reach, const core::IdPipelineResult& result);
  void StartCommands();
  void OnCommand(const drivers::AcceptedCommand& command);
  // Logs the commands rejected since the last line, per verdict: at once for the first, then at
  // most once a second with a count (" xN"), every pending count when `flush` (an operator's
  // audit trail that a flood cannot turn into a journal flood).
  void LogRejectedCommands(bool flush);
  void BeginStop(DaemonExit exit);
  void FinishStopWhenSafe();
  std::string Status() const;

  DaemonPlan plan_;
  drivers::Bus& bus_;
  PortFactory make_port_;
  ReloadFunction reload_;
  boost::asio::io_context io_;
  boost::asio::signal_set signals_;
  boost::asio::steady_timer health_timer_;
  boost::asio::steady_timer stop_timer_;
  boost::asio::steady_timer bus_retry_timer_;
  std::unique_ptr<boost::asio::posix::stream_descriptor> bus_fd_;
  drivers::LcmBus* lcm_bus_ = nullptr;  ///< bus_ when it is an LcmBus (else pumped by a test)
  static constexpr double kBusBackoffMinS = 0.1;
  static constexpr double kBusBackoffMaxS = 5.0;
  double bus_backoff_s_ = kBusBackoffMinS;
  int64_t bus_losses_ = 0;
  int64_t bus_reconnects_ = 0;
  LcmPublisher publisher_;
  std::vector<std::unique_ptr<Plc>> plcs_;
  std::vector<std::unique_ptr<Reach>> reaches_;
  std::optional<DaemonPlan> reloaded_plan_;
  std::optional<StateStore> store_;
  std::unique_ptr<core::CommandAuthenticator> authenticator_;
  std::unique_ptr<drivers::CommandReceiver> command_receiver_;
  std::array<int64_t, core::kNumCommandVerdicts> verdicts_logged_{};
  std::array<double, core::kNumCommandVerdicts> verdict_logged_at_s_{};  ///< steady s, 0: never
  DaemonExit exit_ = DaemonExit::kStopped;
  bool stopping_ = false;
  bool ready_ = false;
  double start_steady_s_ = 0.0;
  double stop_deadline_s_ = 0.0;
  double last_watchdog_s_ = 0.0;
  double watchdog_period_s_ = 0.0;  ///< WatchdogSec from systemd, read once at start
};

}  // namespace canalid::daemon
