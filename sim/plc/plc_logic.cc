#include "sim/plc/plc_logic.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::sim::plc {
namespace {

// One move toward target of at most rate * dt; a rate <= 0 means no limit.
double Toward(double value, double target, double rate_per_s, double dt_s) {
  if (rate_per_s <= 0.0) return target;
  const double max_step = rate_per_s * dt_s;
  return value + std::clamp(target - value, -max_step, max_step);
}

}  // namespace

PlcLogic::PlcLogic(const PlcConfig& config, std::vector<double> nominal_structure,
                   std::vector<double> nominal_offtake, double nominal_upstream_m3s, double now_s)
    : config_(config),
      nominal_structure_(std::move(nominal_structure)),
      nominal_offtake_(std::move(nominal_offtake)),
      nominal_upstream_(nominal_upstream_m3s),
      structure_setpoint_(nominal_structure_),
      structure_setting_(nominal_structure_),
      offtake_setpoint_(nominal_offtake_),
      upstream_setpoint_(nominal_upstream_m3s),
      upstream_flow_(nominal_upstream_m3s),
      last_advance_s_(now_s),
      last_heartbeat_change_s_(now_s) {
  const std::size_t n = config_.pools.size();
  if (nominal_structure_.size() != n || nominal_offtake_.size() != n) {
    throw std::invalid_argument(
        "PlcLogic: nominal_structure (" + std::to_string(nominal_structure_.size()) +
        ") and nominal_offtake (" + std::to_string(nominal_offtake_.size()) +
        ") must have one value per PLC pool (" + std::to_string(n) + ")");
  }
}

double PlcLogic::Clamp(double value, double lo, double hi) {
  const double c = std::isnan(value) ? lo : std::clamp(value, lo, hi);
  clamped_ = c != value;
  return c;
}

double PlcLogic::SetStructureSetpoint(int record, double value) {
  const PoolPlcConfig& p = config_.pools.at(static_cast<std::size_t>(record));
  if (heartbeat_lost_) return structure_setpoint_[static_cast<std::size_t>(record)];
  structure_setpoint_[static_cast<std::size_t>(record)] =
      Clamp(value, p.setpoint_min, p.setpoint_max);
  return structure_setpoint_[static_cast<std::size_t>(record)];
}

double PlcLogic::SetOfftakeSetpoint(int record, double value) {
  const PoolPlcConfig& p = config_.pools.at(static_cast<std::size_t>(record));
  if (heartbeat_lost_) return offtake_setpoint_[static_cast<std::size_t>(record)];
  offtake_setpoint_[static_cast<std::size_t>(record)] = Clamp(value, p.offtake_min, p.offtake_max);
  return offtake_setpoint_[static_cast<std::size_t>(record)];
}

double PlcLogic::SetUpstreamSetpoint(double value_m3s) {
  if (heartbeat_lost_) return upstream_setpoint_;
  upstream_setpoint_ = Clamp(value_m3s, config_.upstream_min_m3s, config_.upstream_max_m3s);
  return upstream_setpoint_;
}

void PlcLogic::Heartbeat(std::uint16_t value, double now_s) {
  if (value == heartbeat_) return;
  heartbeat_ = value;
  last_heartbeat_change_s_ = now_s;
  heartbeat_lost_ = false;
}

void PlcLogic::RestoreNominal() {
  structure_setpoint_ = nominal_structure_;
  offtake_setpoint_ = nominal_offtake_;
  upstream_setpoint_ = nominal_upstream_;
}

void PlcLogic::Advance(double now_s) {
  const double dt_s = std::max(0.0, now_s - last_advance_s_);
  last_advance_s_ = std::max(last_advance_s_, now_s);
  // The watchdog acts before the motion so that the first step after the timeout already moves
  // toward the nominal settings.
  if (config_.heartbeat_timeout_s > 0.0 && !heartbeat_lost_ &&
      now_s - last_heartbeat_change_s_ >= config_.heartbeat_timeout_s) {
    heartbeat_lost_ = true;
    RestoreNominal();
  }
  for (int i = 0; i < num_records(); ++i) {
    structure_setting_[static_cast<std::size_t>(i)] =
        Toward(structure_setting_[static_cast<std::size_t>(i)],
               structure_setpoint_[static_cast<std::size_t>(i)],
               config_.pools[static_cast<std::size_t>(i)].rate_per_s, dt_s);
  }
  upstream_flow_ =
      Toward(upstream_flow_, upstream_setpoint_, config_.upstream_rate_m3s_per_s, dt_s);
}

bool PlcLogic::moving() const {
  for (int i = 0; i < num_records(); ++i) {
    if (structure_setting_[static_cast<std::size_t>(i)] !=
        structure_setpoint_[static_cast<std::size_t>(i)])
      return true;
  }
  return false;
}

}  // namespace canalid::sim::plc
