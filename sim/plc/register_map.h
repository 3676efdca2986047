#pragma once
#include <cstdint>

#include "sim/canal.h"
#include "sim/plc/plc_config.h"

namespace canalid::sim::plc {

/// The register map of the emulated PLC (0-based protocol addresses; full table with units in
/// docs/register-map.md).  System registers sit at fixed addresses from 0; the per-pool blocks
/// start at the bases of PlcConfig, one record per entry of PlcConfig::pools, in that order.

// Input registers (function code 4), system block.
inline constexpr int kIrStatus = 0;       ///< status word, bits kStatus*.
inline constexpr int kIrFaults = 1;       ///< bit i set while fault i is active (kFault*).
inline constexpr int kIrTimeFloat = 2;    ///< plant time (s), float32, two registers.
inline constexpr int kIrTimeSeconds = 4;  ///< plant time (whole s), uint32 high word first.
inline constexpr int kIrStepCount = 6;    ///< plant steps done, modulo 65536.
inline constexpr int kIrPoolCount = 7;    ///< number of pool records.
inline constexpr int kIrHeartbeat = 8;    ///< last heartbeat value seen.
inline constexpr int kIrOverruns = 9;     ///< real-time steps that started late, saturated.
inline constexpr int kIrSystemSize = 10;

// Holding registers (function codes 3, 6, 16), system block.
inline constexpr int kHrHeartbeat = 0;             ///< any change feeds the watchdog.
inline constexpr int kHrStep = 1;                  ///< lockstep: write n > 0 to advance n steps.
inline constexpr int kHrUpstreamScaled = 2;        ///< upstream inflow setpoint, flow units, int16.
inline constexpr int kHrUpstreamFloat = 3;         ///< the same as float32 (m^3/s), two registers.
inline constexpr int kHrFaultDelayMs = 10;         ///< every reply delayed by this many ms.
inline constexpr int kHrFaultException = 11;       ///< reads answered with this exception code.
inline constexpr int kHrFaultDrop = 12;            ///< close the connection on the next n requests.
inline constexpr int kHrFaultStuckMask = 13;       ///< bit i: pool record i's level sensors frozen.
inline constexpr int kHrFaultSpikeMask = 14;       ///< bit i: pool record i's level sensors spike.
inline constexpr int kHrFaultSpikeAmplitude = 15;  ///< spike height, int16 level units.
inline constexpr int kHrFaultSpikePeriod = 16;     ///< spike every n-th step (0 means 2).
inline constexpr int kHrSystemSize = 20;

// Status word bits.
inline constexpr std::uint16_t kStatusRunning = 1u << 0;
inline constexpr std::uint16_t kStatusHeartbeatLost = 1u << 1;
inline constexpr std::uint16_t kStatusLockstep = 1u << 2;
inline constexpr std::uint16_t kStatusFaultActive = 1u << 3;
inline constexpr std::uint16_t kStatusPlantFailed = 1u << 4;
inline constexpr std::uint16_t kStatusMoving = 1u << 5;
inline constexpr std::uint16_t kStatusClamped = 1u << 6;

// Fault word bits (input register kIrFaults).
inline constexpr std::uint16_t kFaultDelay = 1u << 0;
inline constexpr std::uint16_t kFaultException = 1u << 1;
inline constexpr std::uint16_t kFaultDrop = 1u << 2;
inline constexpr std::uint16_t kFaultStuck = 1u << 3;
inline constexpr std::uint16_t kFaultSpike = 1u << 4;

/// Fields of one pool record in the input blocks: the 16-bit block has one register per field
/// (stride kPoolInputFields), the float block two (stride 2 kPoolInputFields).
enum PoolInputField : int {
  kInflow = 0,           ///< flow entering the pool (m^3/s)
  kOutflow = 1,          ///< flow leaving it at the downstream end, structure + offtake (m^3/s)
  kLevelDownstream = 2,  ///< depth above the downstream sill (m)
  kSetting = 3,          ///< actual structure setting: gate opening / crest (m) or pump flow
  kSetpoint = 4,         ///< structure setpoint the PLC is driving toward (same unit)
  kLevelUpstream = 5,    ///< depth at the upstream end of the pool (m)
  kOfftakeFlow = 6,      ///< offtake flow (m^3/s)
  kStructureFlow = 7,    ///< flow through the structure (m^3/s)
};
inline constexpr int kPoolInputFields = 8;

/// Fields of one pool record in the holding blocks (same strides rule).
enum PoolHoldingField : int {
  kStructureSetpoint = 0,  ///< gate opening / crest (m) or pump flow (m^3/s)
  kOfftakeSetpoint = 1,    ///< offtake flow (m^3/s) or orifice area (m^2)
};
inline constexpr int kPoolHoldingFields = 2;

/// Address of a field of pool record `record` in the 16-bit / float input blocks.
inline int InputScaledAddress(const PlcConfig& c, int record, int field) {
  return c.input_scaled_base + record * kPoolInputFields + field;
}
inline int InputFloatAddress(const PlcConfig& c, int record, int field) {
  return c.input_float_base + 2 * (record * kPoolInputFields + field);
}
inline int HoldingScaledAddress(const PlcConfig& c, int record, int field) {
  return c.holding_scaled_base + record * kPoolHoldingFields + field;
}
inline int HoldingFloatAddress(const PlcConfig& c, int record, int field) {
  return c.holding_float_base + 2 * (record * kPoolHoldingFields + field);
}

/// Number of input / holding registers the map needs (one past the highest address).
int InputRegisterCount(const PlcConfig& config);
int HoldingRegisterCount(const PlcConfig& config);

/// The 16-bit unit of a structure setting or setpoint: setting_unit_m for gates and weirs,
/// flow_unit_m3s for pumps.
double StructureUnit(const PlcConfig& config, Structure::Type type);
/// The 16-bit unit of an offtake setpoint: area_unit_m2 for orifices, flow_unit_m3s otherwise.
double OfftakeUnit(const PlcConfig& config, Offtake::Type type);

}  // namespace canalid::sim::plc
