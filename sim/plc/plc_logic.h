#pragma once
#include <cstdint>
#include <vector>

#include "sim/plc/plc_config.h"

namespace canalid::sim::plc {

/// The PLC's local logic, with time passed in (plant seconds), no I/O:
///  - setpoints are clamped to the PLC's limits (PoolPlcConfig, PlcConfig::upstream_*);
///  - each actual structure setting moves toward its setpoint by at most rate_per_s * dt per
///    Advance (no limit when the rate is 0); offtake setpoints apply at once; the upstream inflow
///    ramps at upstream_rate_m3s_per_s (0: at once);
///  - heartbeat watchdog: when the heartbeat value has not changed for heartbeat_timeout_s
///    (> 0), every setpoint returns to its nominal value and heartbeat_lost() is true; setpoint
///    writes are ignored until the heartbeat changes again.
/// Records are indexed as PlcConfig::pools.  Not thread-safe; allocates only in the constructor.
class PlcLogic final {
 public:
  /// @param nominal_structure, nominal_offtake one value per record (the steady-state settings).
  /// @throws std::invalid_argument if the sizes differ from config.pools.size().
  PlcLogic(const PlcConfig& config, std::vector<double> nominal_structure,
           std::vector<double> nominal_offtake, double nominal_upstream_m3s, double now_s);

  /// Sets a setpoint (clamped); returns the setpoint in force afterwards.  @pre 0 <= record < n.
  double SetStructureSetpoint(int record, double value);
  double SetOfftakeSetpoint(int record, double value);
  double SetUpstreamSetpoint(double value_m3s);
  /// Feeds the watchdog: a value different from the last one restarts it at now_s.
  void Heartbeat(std::uint16_t value, double now_s);
  /// Moves the actual settings toward their setpoints over now_s - (time of the previous
  /// Advance) and runs the watchdog.  Time going backwards is treated as no time elapsed.
  void Advance(double now_s);

  int num_records() const { return static_cast<int>(structure_setpoint_.size()); }
  double structure_setpoint(int record) const {
    return structure_setpoint_.at(static_cast<std::size_t>(record));
  }
  double structure_setting(int record) const {
    return structure_setting_.at(static_cast<std::size_t>(record));
  }
  double offtake_setpoint(int record) const {
    return offtake_setpoint_.at(static_cast<std::size_t>(record));
  }
  double upstream_setpoint_m3s() const { return upstream_setpoint_; }
  double upstream_flow_m3s() const { return upstream_flow_; }
  double nominal_structure(int record) const {
    return nominal_structure_.at(static_cast<std::size_t>(record));
  }
  bool heartbeat_lost() const { return heartbeat_lost_; }
  std::uint16_t heartbeat() const { return heartbeat_; }
  /// True if the last Set*Setpoint call had to clamp its value.
  bool clamped() const { return clamped_; }
  /// True while some structure setting differs from its setpoint.
  bool moving() const;

 private:
  double Clamp(double value, double lo, double hi);
  void RestoreNominal();

  PlcConfig config_;
  std::vector<double> nominal_structure_;
  std::vector<double> nominal_offtake_;
  double nominal_upstream_;
  std::vector<double> structure_setpoint_;
  std::vector<double> structure_setting_;
  std::vector<double> offtake_setpoint_;
  double upstream_setpoint_;
  double upstream_flow_;
  double last_advance_s_;
  double last_heartbeat_change_s_;
  std::uint16_t heartbeat_ = 0;
  bool heartbeat_lost_ = false;
  bool clamped_ = false;
};

}  // namespace canalid::sim::plc
