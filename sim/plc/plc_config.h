#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "core/registers/register_codec.h"
#include "sim/canal.h"

namespace canalid::sim::plc {

/// What the PLC does for one pool of the canal (one entry of the register map, in order).
/// The structure setpoint is in the structure's own unit: opening (m) for a gate, crest height
/// above the sill (m) for a weir, flow (m^3/s) for a pump; the offtake setpoint is the offtake's
/// setting (m^3/s for a fixed offtake, orifice area m^2 for an orifice).
struct PoolPlcConfig {
  std::string name;  ///< the canal pool's name
  int pool = 0;      ///< index of that pool in Canal::pools
  double setpoint_min = 0.0;
  double setpoint_max = 0.0;
  /// Largest travel of the actual structure setting per second of plant time toward its
  /// setpoint (m/s or m^3/s per s); 0 means no limit (the setting follows at once).
  double rate_per_s = 0.0;
  double offtake_min = 0.0;
  double offtake_max = 0.0;
};

/// The PLC emulation: plant step, watchdog, register encodings and per-pool limits.  Keys, units
/// and defaults: config/sim/plc/asce2.toml and docs/register-map.md.
struct PlcConfig {
  double plant_step_s = 10.0;        ///< plant time step (s of canal time).
  double heartbeat_timeout_s = 0.0;  ///< plant seconds without a heartbeat change; 0 disables.
  core::WordOrder word_order = core::WordOrder::kHighWordFirst;  ///< of the float registers
  double level_unit_m = 0.001;    ///< one count of a 16-bit level register (m).
  double flow_unit_m3s = 0.001;   ///< one count of a 16-bit flow register (m^3/s).
  double setting_unit_m = 0.001;  ///< one count of a 16-bit gate/weir setting (m).
  double area_unit_m2 = 0.0001;   ///< one count of a 16-bit orifice area (m^2).
  int input_scaled_base = 100;    ///< first input register of the per-pool 16-bit block.
  int input_float_base = 300;     ///< first input register of the per-pool float block.
  int holding_scaled_base = 100;  ///< first holding register of the 16-bit setpoints.
  int holding_float_base = 300;   ///< first holding register of the float setpoints.
  double upstream_min_m3s = 0.0;  ///< range of the upstream inflow setpoint (m^3/s).
  double upstream_max_m3s = 0.0;
  double upstream_rate_m3s_per_s = 0.0;  ///< ramp limit of the inflow, 0 means none.
  std::vector<PoolPlcConfig> pools;
};

/// A PLC for every pool of `canal`, with ranges wide enough for any sensible command: gates and
/// weirs 0 .. bank depth (at least 2 x target depth), pumps and offtakes 0 .. 5 x the upstream
/// flow, no rate limits, no heartbeat watchdog.
PlcConfig DefaultPlcConfig(const Canal& canal);

/// Loads a PLC file for `canal` (pool names must exist in it).  Unknown keys are errors.
/// @throws ConfigError listing every problem with file:line:column.
PlcConfig LoadPlcConfig(const std::string& path, const Canal& canal);
/// Parses `text` as LoadPlcConfig parses a file's contents; messages name the file `name`.
/// @throws ConfigError listing every problem with name:line:column.
PlcConfig ParsePlcConfig(std::string_view text, const std::string& name, const Canal& canal);

/// Checks ranges and that no two register blocks overlap.
/// @throws std::invalid_argument naming the field and the value.
void ValidatePlcConfig(const PlcConfig& config);

}  // namespace canalid::sim::plc
