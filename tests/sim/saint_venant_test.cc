#include "sim/saint_venant.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim/canal_config.h"

namespace canalid::sim {
namespace {

const std::string kSource = CANALID_SOURCE_DIR;
const std::string kReference = CANALID_REFERENCE_DIR;

TEST(SaintVenantCanal, FullCanal2StaysAtItsSteadyState) {
  const Canal canal = LoadCanal(kSource + "/config/sim/asce-canal2.toml");
  SaintVenantCanal plant(canal);
  ASSERT_EQ(plant.num_pools(), 8);
  for (int p = 0; p < 8; ++p) {
    EXPECT_NEAR(plant.DownstreamDepth(p), canal.pools[static_cast<std::size_t>(p)].target_depth_m,
                1e-12);
    if (p < 7) {
      EXPECT_GT(plant.structure_setting(p), 0.0) << "gate opening of pool " << p + 1;
    }
  }
  std::vector<double> before;
  for (int p = 0; p < 8; ++p) {
    for (int i = 0; i < plant.num_nodes(p); ++i) before.push_back(plant.depth_m(p, i));
  }
  for (int k = 0; k < 360; ++k) plant.Step(10.0);
  // The start is the discrete steady state of the scheme, so nothing may move beyond the
  // Newton tolerance (1e-10 m per step) accumulated over an hour.
  std::size_t n = 0;
  for (int p = 0; p < 8; ++p) {
    for (int i = 0; i < plant.num_nodes(p); ++i) {
      EXPECT_NEAR(plant.depth_m(p, i), before[n++], 1e-7);
    }
  }
  EXPECT_NEAR(plant.PoolOutflow(7), 4.0, 1e-7);
}

double TestVolume(const SaintVenantCanal& plant);

TEST(SaintVenantCanal, FullCanal1StaysAtItsSteadyState) {
  const Canal canal = LoadCanal(kSource + "/config/sim/asce-canal1.toml");
  SaintVenantCanal plant(canal);
  std::vector<double> before;
  before.reserve(8);
  for (int p = 0; p < 8; ++p) before.push_back(plant.DownstreamDepth(p));
  for (int k = 0; k < 360; ++k) plant.Step(10.0);
  // Same bound as for canal 2: Newton tolerance accumulated over an hour.
  for (int p = 0; p < 8; ++p)
    EXPECT_NEAR(plant.DownstreamDepth(p), before[static_cast<std::size_t>(p)], 1e-7) << p;
  EXPECT_NEAR(plant.StructureFlow(7), 0.6, 1e-7);
}

// A reservoir upstream, a free weir, an orifice offtake and a free gate at the end: after the
// reservoir rises the canal must settle to a new steady state in which every structure passes
// the same flow, with volume conserved on the way.
TEST(SaintVenantCanal, ReservoirWeirOrificeAndFreeGateSettle) {
  Canal c;
  c.name = "mixed";
  c.upstream.type = UpstreamBoundary::Type::kLevel;
  c.upstream.flow_m3s = 3.0;
  c.max_dx_m = 100.0;
  Pool p;
  p.length_m = 1500;
  p.bottom_width_m = 3;
  p.side_slope = 1.5;
  p.bed_slope = 2e-4;
  p.manning_n = 0.02;
  p.target_depth_m = 1.5;
  c.pools = {p, p, p};
  c.pools[0].name = "1";
  c.pools[1].name = "2";
  c.pools[2].name = "3";
  c.pools[0].structure.type = Structure::Type::kWeir;
  c.pools[0].structure.width_m = 3.0;
  c.pools[0].structure.coefficient = 1.7;
  c.pools[0].structure.drop_m = 0.6;  // keeps the weir free
  c.pools[1].offtake.type = Offtake::Type::kOrifice;
  c.pools[1].offtake.setting = 0.1;  // m^2
  c.pools[1].structure.width_m = 3.0;
  c.pools[2].structure.width_m = 3.0;  // gate to a free outfall
  SaintVenantCanal plant(c);
  const double v0 = TestVolume(plant);
  const double off0 = plant.OfftakeFlow(1);
  EXPECT_NEAR(plant.StructureFlow(0), 3.0, 1e-9);
  EXPECT_NEAR(plant.StructureFlow(2), 3.0 - off0, 1e-9);
  const double level = plant.upstream();
  plant.SetUpstream(level + 0.1);
  double in = 0.0, out = 0.0, before_in = plant.PoolInflow(0), before_out = 3.0;
  for (int k = 0; k < 8640; ++k) {  // 24 h at 10 s
    plant.Step(10.0);
    const double now_in = plant.PoolInflow(0);
    const double now_out = plant.StructureFlow(2) + plant.OfftakeFlow(1);
    in += 5.0 * (before_in + now_in);
    out += 5.0 * (before_out + now_out);
    before_in = now_in;
    before_out = now_out;
  }
  const double q = plant.PoolInflow(0);
  EXPECT_GT(q, 3.2);  // more head, more flow
  // Settled: the weir, the offtake plus gate, and the inflow agree to 0.1 %.
  EXPECT_NEAR(plant.StructureFlow(0), q, 1e-3 * q);
  EXPECT_NEAR(plant.StructureFlow(2) + plant.OfftakeFlow(1), q, 1e-3 * q);
  EXPECT_GT(plant.OfftakeFlow(1), off0);
  // Weir law with Villemonte submergence, from the test's own formula.
  const double h1 = plant.DownstreamDepth(0) - plant.structure_setting(0);
  const double h2 = std::max(plant.UpstreamDepth(1) - 0.6 - plant.structure_setting(0), 0.0);
  EXPECT_NEAR(plant.StructureFlow(0),
              1.7 * 3.0 * std::pow(h1, 1.5) * std::pow(1.0 - std::pow(h2 / h1, 1.5), 0.385), 1e-9);
  EXPECT_LT(std::abs(TestVolume(plant) - v0 - (in - out)), 1e-4 * in);
}

// Independent bookkeeping: volume from the test's own section formula over the nodes, boundary
// flows from what the test commands (inflow, fixed offtakes) and the free-weir law at the end.
double TestVolume(const SaintVenantCanal& plant) {
  double v = 0.0;
  for (int p = 0; p < plant.num_pools(); ++p) {
    const Pool& pool = plant.canal().pools[static_cast<std::size_t>(p)];
    const int n = plant.num_nodes(p);
    for (int i = 0; i < n; ++i) {
      const double y = plant.depth_m(p, i);
      const double a = (pool.bottom_width_m + pool.side_slope * y) * y;
      v += (i == 0 || i == n - 1 ? 0.5 : 1.0) * a * plant.dx_m(p);
    }
  }
  return v;
}

// Newton starts from the state extrapolated along the last step: steps that lengthen 600-fold,
// shorten again, and sudden input changes on a step must still converge (a longer step
// extrapolates no further than one step's change; an overshoot restarts from the last state).
TEST(SaintVenantCanal, StepsOfChangingLengthAndSuddenInputsConverge) {
  SaintVenantCanal plant(LoadCanal(kSource + "/config/sim/asce-canal2.toml"));
  const double gate = plant.structure_setting(3);
  struct Leg {
    double dt_s;
    int steps;
    double inflow_m3s;
    double gate_factor;
  };
  for (const Leg& leg : {Leg{1.0, 20, 11.0, 1.0}, Leg{600.0, 6, 5.5, 0.7}, Leg{0.5, 10, 14.0, 1.2},
                         Leg{120.0, 10, 2.0, 1.0}, Leg{10.0, 30, 11.0, 1.0}}) {
    plant.SetUpstream(leg.inflow_m3s);
    plant.SetStructureSetting(3, gate * leg.gate_factor);
    for (int k = 0; k < leg.steps; ++k) {
      ASSERT_NO_THROW(plant.Step(leg.dt_s)) << "dt " << leg.dt_s << " step " << k;
      ASSERT_LE(plant.last_iterations(), 60);
    }
    for (int p = 0; p < plant.num_pools(); ++p) {
      EXPECT_GT(plant.DownstreamDepth(p), 0.1) << "pool " << p + 1 << " after dt " << leg.dt_s;
      EXPECT_TRUE(std::isfinite(plant.PoolOutflow(p)));
    }
  }
  EXPECT_NEAR(plant.time_s(), 20.0 + 3600.0 + 5.0 + 1200.0 + 300.0, 1e-9);
}

TEST(SaintVenantCanal, MassBalanceOverOneDayOfCanal2Operations) {
  Canal canal = LoadCanal(kSource + "/config/sim/asce-canal2.toml");
  SaintVenantCanal plant(canal);
  const double v0 = TestVolume(plant);
  const double dt = 20.0;
  double net = 0.0, inflow_volume = 0.0;
  auto boundary = [&](double inflow) {
    double off = 0.0;
    for (int p = 0; p < 7; ++p) off += plant.offtake_setting(p);
    const Pool& last = plant.canal().pools[7];
    const double head = std::max(plant.DownstreamDepth(7) - plant.structure_setting(7), 0.0);
    const double weir = last.structure.coefficient * last.structure.width_m * std::pow(head, 1.5);
    return inflow - off - weir;
  };
  double inflow = 11.0;
  double before = boundary(inflow);
  const double gate3 = plant.structure_setting(2);
  for (int k = 1; k <= 4320; ++k) {
    const double t = k * dt;
    // A day of operations: inflow steps and a square wave, an offtake change, a gate move.
    inflow = 11.0 + (t >= 3600 ? 1.0 : 0.0) + (std::fmod(t, 7200.0) < 3600.0 ? 0.5 : -0.5) -
             (t >= 50000 ? 2.0 : 0.0);
    plant.SetUpstream(inflow);
    plant.SetOfftakeSetting(3, t >= 20000 ? 0.4 : 1.0);
    plant.SetStructureSetting(2, t >= 30000 ? 1.1 * gate3 : gate3);
    plant.Step(dt);
    const double after = boundary(inflow);
    net += 0.5 * dt * (before + after);
    inflow_volume += 0.5 * dt * inflow * 2.0;
    before = after;
  }
  inflow_volume *= 0.5;
  const double change = TestVolume(plant) - v0;
  // Target from the brief: < 0.1 % of the volume that entered over 24 h. The scheme conserves
  // mass to Newton tolerance; what remains is the trapezoidal vs theta weighting of boundary
  // flows at step changes, about (theta - 1/2) dt dQ per change.
  EXPECT_LT(std::abs(change - net) / inflow_volume, 1e-3);
  EXPECT_LT(std::abs(change - net), 50.0);
  EXPECT_GT(std::abs(change), 1e4);  // the test moved water, so the balance means something
  EXPECT_NEAR(plant.mass_balance().error_m3, change - net, 1.0);
  RecordProperty("mass_error_m3", std::to_string(change - net));
  RecordProperty("inflow_volume_m3", std::to_string(inflow_volume));
  std::printf(
      "mass balance over 24 h: volume change %.1f m3, net boundary %.1f m3, error %.3g m3 "
      "= %.3g %% of inflow %.0f m3\n",
      change, net, change - net, 100.0 * std::abs(change - net) / inflow_volume, inflow_volume);
}

struct IdzRow {
  int canal;
  int pool;
  double flow_m3s, delay_s, area_m2, p21;
};

std::vector<IdzRow> ReadIdz() {
  std::ifstream in(kReference + "/asce_idz_litrico_fromion_2004.csv");
  std::string line;
  std::getline(in, line);
  std::vector<IdzRow> rows;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell[8];
    for (auto& c : cell) std::getline(ss, c, ',');
    if (cell[1] != "high") continue;
    rows.push_back({std::stoi(cell[0]), std::stoi(cell[2]), std::stod(cell[3]), std::stod(cell[4]),
                    std::stod(cell[5]), std::stod(cell[6])});
  }
  return rows;
}

// Downstream level response of one pool (held outflow) to an inflow step of dq at t = 0.
struct StepResponse {
  std::vector<double> t_s, rise_m;
  // First time the rise exceeds threshold_m (linear interpolation between samples).
  double Crossing(double threshold_m) const {
    for (std::size_t k = 1; k < rise_m.size(); ++k) {
      if (rise_m[k] > threshold_m) {
        return t_s[k - 1] +
               (threshold_m - rise_m[k - 1]) / (rise_m[k] - rise_m[k - 1]) * (t_s[k] - t_s[k - 1]);
      }
    }
    return -1.0;
  }
  // Mid-time of the steepest rise before t_max_s: where the front passes the gauge.
  double Steepest(double t_max_s) const {
    double best = 0.0, when = -1.0;
    for (std::size_t k = 1; k < rise_m.size() && t_s[k] <= t_max_s; ++k) {
      const double s = (rise_m[k] - rise_m[k - 1]) / (t_s[k] - t_s[k - 1]);
      if (s > best) {
        best = s;
        when = 0.5 * (t_s[k] + t_s[k - 1]);
      }
    }
    return when;
  }
};

StepResponse PoolStep(const Pool& source, double flow_m3s, double dq, double dx_m, double dt_s,
                      double duration_s) {
  Canal c;
  c.name = "pool" + source.name;
  c.pools = {source};
  c.pools[0].structure = Structure();
  c.pools[0].structure.type = Structure::Type::kPump;  // held outflow
  c.pools[0].offtake = Offtake();
  c.upstream.flow_m3s = flow_m3s;
  c.max_dx_m = dx_m;
  c.theta = 0.6;
  SaintVenantCanal plant(c);
  const double y0 = plant.DownstreamDepth(0);
  plant.SetUpstream(flow_m3s + dq);
  StepResponse r;
  r.t_s.push_back(0.0);
  r.rise_m.push_back(0.0);
  const long steps = std::lround(duration_s / dt_s);
  for (long k = 1; k <= steps; ++k) {
    plant.Step(dt_s);
    r.t_s.push_back(static_cast<double>(k) * dt_s);
    r.rise_m.push_back(plant.DownstreamDepth(0) - y0);
  }
  return r;
}

// Wave arrival at the downstream end of every high-flow ASCE pool against the IDZ delay tau.
// Arrival = first time the downstream level has risen by half of the IDZ front jump
// p21 * dq (the mid-height of the wave front); for canal 2, also the time of the steepest rise,
// which needs no reference number. The ID definition (late asymptote meets the initial level)
// gives about tau - p21 A instead (see docs/canalsim.md) and is not tested against tau.
TEST(SaintVenantCanal, WaveArrivalMatchesIdzDelayOnAsceCanals) {
  const Canal c1 = LoadCanal(kSource + "/config/sim/asce-canal1.toml");
  const Canal c2 = LoadCanal(kSource + "/config/sim/asce-canal2.toml");
  int checked = 0;
  for (const IdzRow& row : ReadIdz()) {
    const Pool& pool = (row.canal == 1 ? c1 : c2).pools.at(static_cast<std::size_t>(row.pool - 1));
    // Resolve the front: about 60 cells per pool (at most 100 m) and a Courant number near 0.4.
    const double dx = std::min(100.0, pool.length_m / 60.0);
    const double dt = dx / 10.0;
    const double dq = 0.1 * row.flow_m3s;
    const StepResponse r = PoolStep(pool, row.flow_m3s, dq, dx, dt, 3.0 * row.delay_s);
    const double arrival = r.Crossing(0.5 * row.p21 * dq);
    std::printf("canal %d pool %d: tau %.1f s, half-front arrival %.1f s (%+.1f %%)", row.canal,
                row.pool, row.delay_s, arrival, 100.0 * (arrival / row.delay_s - 1.0));
    // 10 % is the brief's tolerance; the scheme's front is smeared over a few cells.
    EXPECT_NEAR(arrival, row.delay_s, 0.1 * row.delay_s)
        << "canal " << row.canal << " pool " << row.pool;
    if (row.canal == 2) {
      const double steepest = r.Steepest(2.0 * row.delay_s);
      std::printf(", steepest rise %.1f s (%+.1f %%)", steepest,
                  100.0 * (steepest / row.delay_s - 1.0));
      EXPECT_NEAR(steepest, row.delay_s, 0.1 * row.delay_s) << "pool " << row.pool;
    }
    std::printf("\n");
    ++checked;
  }
  EXPECT_EQ(checked, 16);
}

}  // namespace
}  // namespace canalid::sim
