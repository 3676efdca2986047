#include "sim/level_pid.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::sim {
namespace {

void Require(bool ok, const char* field, double value, const char* range) {
  if (ok) return;
  std::ostringstream os;
  os << "LevelPid: " << field << " = " << value << " must be " << range;
  throw std::invalid_argument(os.str());
}

}  // namespace

LevelPid::LevelPid(const LevelPidConfig& config) : config_(config) {
  Require(std::isfinite(config.setpoint_m), "setpoint_m", config.setpoint_m, "finite");
  Require(std::isfinite(config.kp) && config.kp >= 0.0, "kp", config.kp, ">= 0");
  Require(std::isfinite(config.ki) && config.ki >= 0.0, "ki", config.ki, ">= 0");
  Require(std::isfinite(config.kd) && config.kd >= 0.0, "kd", config.kd, ">= 0");
  Require(std::isfinite(config.min_flow_m3s) && config.min_flow_m3s >= 0.0, "min_flow_m3s",
          config.min_flow_m3s, ">= 0");
  Require(std::isfinite(config.max_flow_m3s) && config.max_flow_m3s >= config.min_flow_m3s,
          "max_flow_m3s", config.max_flow_m3s, ">= min_flow_m3s");
  Require(std::isfinite(config.sample_time_s) && config.sample_time_s > 0.0, "sample_time_s",
          config.sample_time_s, "> 0");
  Reset(config.min_flow_m3s, config.setpoint_m);
}

void LevelPid::Reset(double flow_m3s, double level_m) {
  output_ = std::clamp(flow_m3s, config_.min_flow_m3s, config_.max_flow_m3s);
  integral_ = output_;
  previous_level_m_ = level_m;
  saturated_ = false;
}

double LevelPid::Update(double level_m) {
  const double sign = config_.direct_action ? 1.0 : -1.0;
  const double ts = config_.sample_time_s;
  const double error = sign * (config_.setpoint_m - level_m);
  const double derivative = -sign * config_.kd * (level_m - previous_level_m_) / ts;
  previous_level_m_ = level_m;
  const double candidate = integral_ + config_.ki * ts * error;
  const double raw = config_.kp * error + candidate + derivative;
  // Integrate unless that would drive the output further past the limit it already exceeds.
  const bool high = raw > config_.max_flow_m3s && error > 0.0;
  const bool low = raw < config_.min_flow_m3s && error < 0.0;
  if (!high && !low) integral_ = candidate;
  const double unclamped = config_.kp * error + integral_ + derivative;
  output_ = std::clamp(unclamped, config_.min_flow_m3s, config_.max_flow_m3s);
  saturated_ = output_ != unclamped;
  return output_;
}

}  // namespace canalid::sim
