#include "sim/plc/plc_simulation.h"

#include <cmath>
#include <span>
#include <stdexcept>

#include "core/registers/register_codec.h"

namespace canalid::sim::plc {
namespace {

// The two registers of a 32-bit value at `at`.
std::span<std::uint16_t, 2> Pair(std::vector<std::uint16_t>& registers, int at) {
  return std::span(registers).subspan(static_cast<std::size_t>(at)).first<2>();
}

std::vector<double> NominalStructures(const SaintVenantCanal& plant, const PlcConfig& config) {
  std::vector<double> v;
  for (const PoolPlcConfig& p : config.pools) v.push_back(plant.structure_setting(p.pool));
  return v;
}

std::vector<double> NominalOfftakes(const SaintVenantCanal& plant, const PlcConfig& config) {
  std::vector<double> v;
  for (const PoolPlcConfig& p : config.pools) v.push_back(plant.offtake_setting(p.pool));
  return v;
}

bool Touches(int first, int count, int address, int width) {
  return first < address + width && address < first + count;
}

}  // namespace

PlcSimulation::PlcSimulation(const Canal& canal, const PlcConfig& config, bool lockstep)
    : config_((ValidatePlcConfig(config), config)),
      plant_(canal),
      logic_(config_, NominalStructures(plant_, config_), NominalOfftakes(plant_, config_),
             plant_.upstream(), plant_.time_s()),
      lockstep_(lockstep),
      input_(static_cast<std::size_t>(InputRegisterCount(config_)), 0),
      holding_(static_cast<std::size_t>(HoldingRegisterCount(config_)), 0),
      stuck_upstream_m_(config_.pools.size(), 0.0),
      stuck_downstream_m_(config_.pools.size(), 0.0) {
  for (const PoolPlcConfig& p : config_.pools) {
    if (p.pool < 0 || p.pool >= plant_.num_pools()) {
      throw std::invalid_argument("PLC pool '" + p.name + "' has index " + std::to_string(p.pool) +
                                  " outside the canal's " + std::to_string(plant_.num_pools()) +
                                  " pools");
    }
  }
  PublishHoldings();
  PublishInputs();
}

void PlcSimulation::Step() {
  if (plant_failed_) return;
  const double t_next_s = plant_.time_s() + config_.plant_step_s;
  // The plant takes the inputs set now as their values at the end of the step, so the PLC
  // moves its actuators to where they are at t_next first.
  logic_.Advance(t_next_s);
  for (int r = 0; r < logic_.num_records(); ++r) {
    const int pool = config_.pools[static_cast<std::size_t>(r)].pool;
    plant_.SetStructureSetting(pool, logic_.structure_setting(r));
    plant_.SetOfftakeSetting(pool, logic_.offtake_setpoint(r));
  }
  if (plant_.canal().upstream.type == UpstreamBoundary::Type::kFlow) {
    plant_.SetUpstream(logic_.upstream_flow_m3s());
  }
  try {
    plant_.Step(config_.plant_step_s);
    ++steps_;
  } catch (const std::runtime_error&) {
    plant_failed_ = true;
  }
  PublishHoldings();
  PublishInputs();
}

bool PlcSimulation::TakeDrop() {
  if (holding_[kHrFaultDrop] == 0) return false;
  --holding_[kHrFaultDrop];
  return true;
}

void PlcSimulation::OnHoldingWrite(int first, int count) {
  const double now_s = plant_.time_s();
  if (Touches(first, count, kHrHeartbeat, 1)) logic_.Heartbeat(holding_[kHrHeartbeat], now_s);
  const core::WordOrder order = config_.word_order;
  bool any_setpoint = false;
  if (plant_.canal().upstream.type == UpstreamBoundary::Type::kFlow) {
    if (Touches(first, count, kHrUpstreamScaled, 1)) {
      logic_.SetUpstreamSetpoint(
          core::DecodeScaled16(holding_[kHrUpstreamScaled], config_.flow_unit_m3s));
      any_setpoint = true;
    }
    if (Touches(first, count, kHrUpstreamFloat, 2)) {
      logic_.SetUpstreamSetpoint(core::DecodeFloat32(Pair(holding_, kHrUpstreamFloat), order));
      any_setpoint = true;
    }
  }
  for (int r = 0; r < logic_.num_records(); ++r) {
    const Pool& pool =
        plant_.canal()
            .pools[static_cast<std::size_t>(config_.pools[static_cast<std::size_t>(r)].pool)];
    const double su = StructureUnit(config_, pool.structure.type);
    const double ou = OfftakeUnit(config_, pool.offtake.type);
    const int ss = HoldingScaledAddress(config_, r, kStructureSetpoint);
    const int os = HoldingScaledAddress(config_, r, kOfftakeSetpoint);
    const int sf = HoldingFloatAddress(config_, r, kStructureSetpoint);
    const int of = HoldingFloatAddress(config_, r, kOfftakeSetpoint);
    if (Touches(first, count, ss, 1)) {
      logic_.SetStructureSetpoint(r,
                                  core::DecodeScaled16(holding_[static_cast<std::size_t>(ss)], su));
      any_setpoint = true;
    }
    if (Touches(first, count, sf, 2)) {
      logic_.SetStructureSetpoint(r, core::DecodeFloat32(Pair(holding_, sf), order));
      any_setpoint = true;
    }
    if (Touches(first, count, os, 1)) {
      logic_.SetOfftakeSetpoint(r,
                                core::DecodeScaled16(holding_[static_cast<std::size_t>(os)], ou));
      any_setpoint = true;
    }
    if (Touches(first, count, of, 2)) {
      logic_.SetOfftakeSetpoint(r, core::DecodeFloat32(Pair(holding_, of), order));
      any_setpoint = true;
    }
  }
  if (any_setpoint) clamped_ = logic_.clamped();
  if (Touches(first, count, kHrFaultStuckMask, 1)) {
    const std::uint16_t mask = holding_[kHrFaultStuckMask];
    for (int r = 0; r < logic_.num_records(); ++r) {
      const bool was = (stuck_mask_ >> r) & 1u;
      const bool is = (mask >> r) & 1u;
      if (is && !was) {
        // The sensor freezes at the reading it gives now.
        stuck_upstream_m_[static_cast<std::size_t>(r)] =
            plant_.UpstreamDepth(config_.pools[static_cast<std::size_t>(r)].pool);
        stuck_downstream_m_[static_cast<std::size_t>(r)] =
            plant_.DownstreamDepth(config_.pools[static_cast<std::size_t>(r)].pool);
      }
    }
    stuck_mask_ = mask;
  }
  if (Touches(first, count, kHrStep, 1) && lockstep_) {
    const int n = holding_[kHrStep];
    for (int i = 0; i < n && !plant_failed_; ++i) Step();
  }
  PublishHoldings();
  PublishInputs();
}

void PlcSimulation::PutInput(int record, int field, double value, double unit) {
  input_[static_cast<std::size_t>(InputScaledAddress(config_, record, field))] =
      core::EncodeScaled16(value, unit);
  core::EncodeFloat32(static_cast<float>(value), config_.word_order,
                      Pair(input_, InputFloatAddress(config_, record, field)));
}

void PlcSimulation::PutHolding(int record, int field, double value, double unit) {
  holding_[static_cast<std::size_t>(HoldingScaledAddress(config_, record, field))] =
      core::EncodeScaled16(value, unit);
  core::EncodeFloat32(static_cast<float>(value), config_.word_order,
                      Pair(holding_, HoldingFloatAddress(config_, record, field)));
}

void PlcSimulation::PublishHoldings() {
  holding_[kHrStep] = 0;
  const bool flow_boundary = plant_.canal().upstream.type == UpstreamBoundary::Type::kFlow;
  const double upstream = flow_boundary ? logic_.upstream_setpoint_m3s() : plant_.upstream();
  holding_[kHrUpstreamScaled] =
      core::EncodeScaled16(upstream, flow_boundary ? config_.flow_unit_m3s : config_.level_unit_m);
  core::EncodeFloat32(static_cast<float>(upstream), config_.word_order,
                      Pair(holding_, kHrUpstreamFloat));
  for (int r = 0; r < logic_.num_records(); ++r) {
    const Pool& pool =
        plant_.canal()
            .pools[static_cast<std::size_t>(config_.pools[static_cast<std::size_t>(r)].pool)];
    PutHolding(r, kStructureSetpoint, logic_.structure_setpoint(r),
               StructureUnit(config_, pool.structure.type));
    PutHolding(r, kOfftakeSetpoint, logic_.offtake_setpoint(r),
               OfftakeUnit(config_, pool.offtake.type));
  }
}

double PlcSimulation::Level(int record, double true_depth_m, bool downstream) const {
  if ((stuck_mask_ >> record) & 1u) {
    return downstream ? stuck_downstream_m_[static_cast<std::size_t>(record)]
                      : stuck_upstream_m_[static_cast<std::size_t>(record)];
  }
  if ((holding_[kHrFaultSpikeMask] >> record) & 1u) {
    const int period = holding_[kHrFaultSpikePeriod] == 0 ? 2 : holding_[kHrFaultSpikePeriod];
    if (steps_ % period == 0) {
      return true_depth_m +
             core::DecodeScaled16(holding_[kHrFaultSpikeAmplitude], config_.level_unit_m);
    }
  }
  return true_depth_m;
}

void PlcSimulation::PublishInputs() {
  std::uint16_t faults = 0;
  if (holding_[kHrFaultDelayMs] != 0) faults |= kFaultDelay;
  if (holding_[kHrFaultException] != 0) faults |= kFaultException;
  if (holding_[kHrFaultDrop] != 0) faults |= kFaultDrop;
  if (stuck_mask_ != 0) faults |= kFaultStuck;
  if (holding_[kHrFaultSpikeMask] != 0) faults |= kFaultSpike;
  std::uint16_t status = plant_failed_ ? kStatusPlantFailed : kStatusRunning;
  if (logic_.heartbeat_lost()) status |= kStatusHeartbeatLost;
  if (lockstep_) status |= kStatusLockstep;
  if (faults != 0) status |= kStatusFaultActive;
  if (logic_.moving()) status |= kStatusMoving;
  if (clamped_) status |= kStatusClamped;
  input_[kIrStatus] = status;
  input_[kIrFaults] = faults;
  const double t_s = plant_.time_s();
  core::EncodeFloat32(static_cast<float>(t_s), config_.word_order, Pair(input_, kIrTimeFloat));
  core::EncodeUint32(static_cast<std::uint32_t>(std::floor(t_s)), core::WordOrder::kHighWordFirst,
                     Pair(input_, kIrTimeSeconds));
  input_[kIrStepCount] = static_cast<std::uint16_t>(steps_ & 0xFFFF);
  input_[kIrPoolCount] = static_cast<std::uint16_t>(config_.pools.size());
  input_[kIrHeartbeat] = logic_.heartbeat();
  input_[kIrOverruns] = static_cast<std::uint16_t>(overruns_ > 65535 ? 65535 : overruns_);
  for (int r = 0; r < logic_.num_records(); ++r) {
    const int pool = config_.pools[static_cast<std::size_t>(r)].pool;
    const Structure::Type type =
        plant_.canal().pools[static_cast<std::size_t>(pool)].structure.type;
    const double su = StructureUnit(config_, type);
    const double fu = config_.flow_unit_m3s;
    const double lu = config_.level_unit_m;
    PutInput(r, kInflow, plant_.PoolInflow(pool), fu);
    PutInput(r, kOutflow, plant_.PoolOutflow(pool), fu);
    PutInput(r, kLevelDownstream, Level(r, plant_.DownstreamDepth(pool), true), lu);
    PutInput(r, kSetting, logic_.structure_setting(r), su);
    PutInput(r, kSetpoint, logic_.structure_setpoint(r), su);
    PutInput(r, kLevelUpstream, Level(r, plant_.UpstreamDepth(pool), false), lu);
    PutInput(r, kOfftakeFlow, plant_.OfftakeFlow(pool), fu);
    PutInput(r, kStructureFlow, plant_.StructureFlow(pool), fu);
  }
}

}  // namespace canalid::sim::plc
