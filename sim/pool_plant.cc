#include "sim/pool_plant.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sim/saint_venant.h"

namespace canalid::sim {
namespace {

void RequireStep(double dt_s) {
  if (!(dt_s > 0.0)) {
    throw std::invalid_argument("PoolPlant::Step: dt_s " + std::to_string(dt_s) + " must be > 0");
  }
}

}  // namespace

DelayedInput::DelayedInput(double delay_s, double initial) : delay_s_(delay_s) {
  changes_.emplace_back(-1e300, initial);
}

void DelayedInput::Set(double t_s, double value) {
  if (changes_.back().second == value) return;
  if (changes_.back().first == t_s) {
    changes_.back().second = value;
    return;
  }
  changes_.emplace_back(t_s, value);
}

double DelayedInput::At(double t_s) const {
  double value = changes_.front().second;
  for (const auto& [t, v] : changes_) {
    if (t + delay_s_ > t_s) break;
    value = v;
  }
  return value;
}

void DelayedInput::Forget(double t_s) {
  // Keep the last change that is already in effect at t_s - delay, drop the ones before it.
  while (changes_.size() > 1 && changes_[1].first + delay_s_ <= t_s) changes_.pop_front();
}

IdzPlant::IdzPlant(double delay_s, double area_m2, double p21_s_per_m2, double p22_s_per_m2,
                   double level0_m, double flow0_m3s)
    : area_m2_(area_m2),
      p21_(p21_s_per_m2),
      p22_(p22_s_per_m2),
      level0_m_(level0_m),
      flow0_m3s_(flow0_m3s),
      inflow_(delay_s, flow0_m3s),
      outflow_m3s_(flow0_m3s) {
  if (!(delay_s >= 0.0) || !(area_m2 > 0.0) || !(p21_s_per_m2 >= 0.0) || !(p22_s_per_m2 >= 0.0)) {
    std::ostringstream os;
    os << "IdzPlant: delay_s " << delay_s << " must be >= 0, area_m2 " << area_m2 << " > 0, p21 "
       << p21_s_per_m2 << " and p22 " << p22_s_per_m2 << " >= 0";
    throw std::invalid_argument(os.str());
  }
}

void IdzPlant::SetFlows(double inflow_m3s, double outflow_m3s) {
  inflow_.Set(time_s_, inflow_m3s);
  outflow_m3s_ = outflow_m3s;
}

void IdzPlant::Step(double dt_s) {
  RequireStep(dt_s);
  double volume = 0.0;
  inflow_.ForEachPiece(time_s_, time_s_ + dt_s,
                       [&](double duration, double q) { volume += duration * (q - flow0_m3s_); });
  volume -= dt_s * (outflow_m3s_ - flow0_m3s_);
  storage_m_ += volume / area_m2_;
  time_s_ += dt_s;
  inflow_.Forget(time_s_);
}

double IdzPlant::level_m() const {
  return level0_m_ + storage_m_ + p21_ * (inflow_.At(time_s_) - flow0_m3s_) -
         p22_ * (outflow_m3s_ - flow0_m3s_);
}

FoptdPlant::FoptdPlant(double gain_m_per_m3s, double time_constant_s, double delay_s,
                       double level0_m, double flow0_m3s)
    : gain_(gain_m_per_m3s),
      time_constant_s_(time_constant_s),
      level0_m_(level0_m),
      flow0_m3s_(flow0_m3s),
      inflow_(delay_s, flow0_m3s) {
  if (!(delay_s >= 0.0) || !(time_constant_s > 0.0)) {
    std::ostringstream os;
    os << "FoptdPlant: delay_s " << delay_s << " must be >= 0 and time_constant_s "
       << time_constant_s << " > 0";
    throw std::invalid_argument(os.str());
  }
}

void FoptdPlant::SetFlows(double inflow_m3s, double /*outflow_m3s*/) {
  inflow_.Set(time_s_, inflow_m3s);
}

void FoptdPlant::Step(double dt_s) {
  RequireStep(dt_s);
  // Exact solution of T x' = u - x over each piece where the delayed input is constant.
  inflow_.ForEachPiece(time_s_, time_s_ + dt_s, [&](double duration, double q) {
    const double u = q - flow0_m3s_;
    state_ = u + (state_ - u) * std::exp(-duration / time_constant_s_);
  });
  time_s_ += dt_s;
  inflow_.Forget(time_s_);
}

SaintVenantPool::SaintVenantPool(const Pool& pool, double flow_m3s, double max_dx_m, double theta) {
  Canal c;
  c.name = "pool " + pool.name;
  c.pools = {pool};
  c.pools[0].structure = Structure();
  c.pools[0].structure.type = Structure::Type::kPump;
  c.pools[0].offtake = Offtake();
  c.upstream.flow_m3s = flow_m3s;
  c.max_dx_m = max_dx_m;
  c.theta = theta;
  canal_ = std::make_unique<SaintVenantCanal>(c);
}

SaintVenantPool::~SaintVenantPool() = default;

void SaintVenantPool::SetFlows(double inflow_m3s, double outflow_m3s) {
  canal_->SetUpstream(inflow_m3s);
  canal_->SetStructureSetting(0, outflow_m3s);
}

void SaintVenantPool::Step(double dt_s) {
  RequireStep(dt_s);
  canal_->Step(dt_s);
}

double SaintVenantPool::time_s() const { return canal_->time_s(); }

double SaintVenantPool::level_m() const { return canal_->DownstreamDepth(0); }

}  // namespace canalid::sim
