#pragma once
#include <cstdint>
#include <vector>

#include "sim/canal.h"
#include "sim/plc/plc_config.h"
#include "sim/plc/plc_logic.h"
#include "sim/plc/register_map.h"
#include "sim/saint_venant.h"

namespace canalid::sim::plc {

/// The emulated PLC wired to the plant, without any transport: the Saint-Venant canal, the PLC
/// logic, the sensor faults and the register image (input and holding registers, layout in
/// register_map.h).  A transport (ModbusSlave) serves the image, calls
/// OnHoldingWrite after a master wrote holding registers, and Step on its clock.
/// Not thread-safe.  Allocates only in the constructor.
class PlcSimulation final {
 public:
  /// Builds the plant at its steady state; the nominal setpoints are its settings there.
  /// @param lockstep the plant steps only when the master writes the step register.
  /// @throws std::invalid_argument (canal, PLC config) or std::runtime_error (steady state).
  PlcSimulation(const Canal& canal, const PlcConfig& config, bool lockstep);

  /// One plant step of config().plant_step_s: the PLC logic moves the settings, the plant
  /// advances, the input registers are refreshed.  After a plant failure (Newton did not
  /// converge) nothing steps any more and the status word says kStatusPlantFailed.
  void Step();

  /// To be called after a master wrote holding registers [first, first + count): applies
  /// heartbeat, setpoints, fault switches and the lockstep step command (the steps are done
  /// before this returns), then rewrites the holding registers from the PLC state (clamped
  /// setpoints, step register back to 0).
  void OnHoldingWrite(int first, int count);
  /// Rewrites the holding registers that the PLC owns (setpoints, step register) from its state.
  void PublishHoldings();

  /// Transport faults, as switched by the master (see register_map.h).
  int response_delay_ms() const { return holding_[kHrFaultDelayMs]; }
  int read_exception_code() const { return holding_[kHrFaultException]; }
  /// True if this request's connection must be dropped (consumes one of the drop count).
  bool TakeDrop();

  std::vector<std::uint16_t>& input_registers() { return input_; }
  std::vector<std::uint16_t>& holding_registers() { return holding_; }
  const SaintVenantCanal& plant() const { return plant_; }
  const PlcLogic& logic() const { return logic_; }
  const PlcConfig& config() const { return config_; }
  bool lockstep() const { return lockstep_; }
  bool plant_failed() const { return plant_failed_; }
  long steps() const { return steps_; }
  void set_overruns(int overruns) { overruns_ = overruns; }

 private:
  void PublishInputs();
  double Level(int record, double true_depth_m, bool downstream) const;
  void PutInput(int record, int field, double value, double unit);
  void PutHolding(int record, int field, double value, double unit);

  PlcConfig config_;
  SaintVenantCanal plant_;
  PlcLogic logic_;
  bool lockstep_;
  bool plant_failed_ = false;
  long steps_ = 0;
  int overruns_ = 0;
  std::vector<std::uint16_t> input_;
  std::vector<std::uint16_t> holding_;
  std::vector<double> stuck_upstream_m_;
  std::vector<double> stuck_downstream_m_;
  std::uint16_t stuck_mask_ = 0;
  bool clamped_ = false;
};

}  // namespace canalid::sim::plc
