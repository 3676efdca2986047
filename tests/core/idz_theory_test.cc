// canalid theory's IDZ model against the published table of Litrico & Fromion (2004) for the 16
// pools of the ASCE test canals at both flows (tests/data/reference), and against closed forms.
#include "core/hydraulics/idz_theory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/hydraulics/trapezoid_section.h"

namespace canalid::core {
namespace {

std::vector<std::vector<std::string>> ReadRows(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

// canal,pool,length_m,bottom_width_m,side_slope_h_per_v,bed_slope,manning_n,bank_depth_m,
// target_depth_m
std::map<std::pair<int, int>, PoolGeometry> AsceGeometry() {
  std::map<std::pair<int, int>, PoolGeometry> pools;
  for (const auto& r : ReadRows(std::string(CANALID_REFERENCE_DIR) + "/asce_test_canals.csv")) {
    PoolGeometry g;
    g.length_m = std::stod(r.at(2));
    g.bottom_width_m = std::stod(r.at(3));
    g.side_slope = std::stod(r.at(4));
    g.bed_slope = std::stod(r.at(5));
    g.manning_n = std::stod(r.at(6));
    g.downstream_depth_m = std::stod(r.at(8));
    pools[{std::stoi(r.at(0)), std::stoi(r.at(1))}] = g;
  }
  return pools;
}

double RelativeError(double got, double want) { return std::abs(got / want - 1.0); }

TEST(IdzTheory, ReproducesThePublishedTableForAll32Pools) {
  const auto geometry = AsceGeometry();
  ASSERT_EQ(geometry.size(), 16u);
  // canal,regime,pool,flow_m3s,delay_s,backwater_area_m2,p21_s_per_m2,p22_s_per_m2
  const auto rows =
      ReadRows(std::string(CANALID_REFERENCE_DIR) + "/asce_idz_litrico_fromion_2004.csv");
  ASSERT_EQ(rows.size(), 32u);
  double worst[4] = {0, 0, 0, 0};
  for (const auto& r : rows) {
    const std::string where = "canal " + r.at(0) + " " + r.at(1) + " pool " + r.at(2);
    const PoolGeometry& pool = geometry.at({std::stoi(r.at(0)), std::stoi(r.at(2))});
    const IdzModel m = IdzFromGeometry(pool, std::stod(r.at(3))).model;
    const double errors[4] = {RelativeError(m.delay_s, std::stod(r.at(4))),
                              RelativeError(m.area_m2, std::stod(r.at(5))),
                              RelativeError(m.p21_s_per_m2, std::stod(r.at(6))),
                              RelativeError(m.p22_s_per_m2, std::stod(r.at(7)))};
    EXPECT_LT(errors[0], 0.02) << where << ": delay " << m.delay_s << " s";
    EXPECT_LT(errors[1], 0.02) << where << ": area " << m.area_m2 << " m2";
    EXPECT_LT(errors[2], 0.05) << where << ": p21 " << m.p21_s_per_m2;
    EXPECT_LT(errors[3], 0.05) << where << ": p22 " << m.p22_s_per_m2;
    for (int i = 0; i < 4; ++i) worst[i] = std::max(worst[i], errors[i]);
  }
  std::cout << "worst relative errors: delay " << worst[0] << ", area " << worst[1] << ", p21 "
            << worst[2] << ", p22 " << worst[3] << "\n";
}

// A pool whose downstream depth is the normal depth is uniform from end to end: its delay is the
// travel time L/(C + V) of a downstream wave and its areas follow from the low-frequency limit of
// the uniform-flow transfer functions, Ad = T^2 (C^2 - V^2)/delta (1 - e^{-delta L/(T (C^2 -
// V^2))}), written out here from the section alone.
TEST(IdzTheory, UniformPoolMatchesTheClosedForms) {
  PoolGeometry pool{5000.0, 4.0, 1.5, 3e-4, 0.02, 0.0};
  const double flow = 6.0;
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  const double yn = section.NormalDepth(flow, pool.bed_slope);
  EXPECT_NEAR(section.FrictionSlope(yn, flow), pool.bed_slope, 1e-12);
  pool.downstream_depth_m = yn;
  const IdzTheory theory = IdzFromGeometry(pool, flow);
  EXPECT_DOUBLE_EQ(theory.uniform_length_m, pool.length_m);
  EXPECT_NEAR(theory.upstream_depth_m, yn, 1e-9);
  const double a = section.Area(yn), t = section.TopWidth(yn), p = section.Perimeter(yn);
  const double c = std::sqrt(kGravity * a / t), v = flow / a, f2 = v * v / (c * c);
  const double kappa = 7.0 / 3.0 - 4.0 * a * 2.0 * std::sqrt(1.0 + 1.5 * 1.5) / (3.0 * t * p);
  const double delta = kGravity * t * (1.0 + kappa) * pool.bed_slope;
  const double w = t * (c * c - v * v);
  EXPECT_NEAR(theory.model.delay_s, pool.length_m / (c + v), 1e-9);
  EXPECT_NEAR(theory.model.upstream_delay_s, pool.length_m / (c - v), 1e-9);
  EXPECT_NEAR(theory.model.area_m2, t * w / delta * (1.0 - std::exp(-delta * pool.length_m / w)),
              1e-9 * theory.model.area_m2);
  // The outflow's direct gain lies between the two local wave impedances 1/(T (C +- V)).
  EXPECT_GT(theory.model.p22_s_per_m2, 1.0 / (t * (c + v)));
  EXPECT_LT(theory.model.p22_s_per_m2, 1.0 / (t * (c - v)));
  EXPECT_LT(f2, 1.0);
}

// A short pool with a nearly still water surface is a reservoir: its backwater area is its
// surface area T L, and both delays are L/C.
TEST(IdzTheory, ShortStillPoolIsAReservoir) {
  const PoolGeometry pool{50.0, 2.0, 1.0, 0.0, 0.015, 1.5};
  const IdzTheory theory = IdzFromGeometry(pool, 1e-3);
  const TrapezoidSection section(2.0, 1.0, 0.015);
  EXPECT_DOUBLE_EQ(theory.uniform_length_m, 0.0);
  EXPECT_NEAR(theory.model.area_m2, section.TopWidth(1.5) * 50.0, 1e-3 * theory.model.area_m2);
  const double c = std::sqrt(kGravity * section.Area(1.5) / section.TopWidth(1.5));
  EXPECT_NEAR(theory.model.delay_s, 50.0 / c, 1e-3 * theory.model.delay_s);
  EXPECT_NEAR(theory.model.upstream_delay_s, 50.0 / c, 1e-3 * theory.model.delay_s);
}

TEST(IdzTheory, BadInputIsNamed) {
  const PoolGeometry good{3000.0, 7.0, 1.5, 1e-4, 0.02, 2.1};
  auto message = [](const PoolGeometry& pool, double flow) {
    try {
      IdzFromGeometry(pool, flow);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(good, -1.0).find("flow -1"), std::string::npos);
  EXPECT_NE(message(good, std::nan("")).find("flow"), std::string::npos);
  PoolGeometry shallow = good;
  shallow.downstream_depth_m = 0.05;
  EXPECT_NE(message(shallow, 10.0).find("not subcritical"), std::string::npos);
  PoolGeometry zero_length = good;
  zero_length.length_m = 0.0;
  EXPECT_NE(message(zero_length, 10.0).find("length_m 0"), std::string::npos);
  PoolGeometry rough = good;
  rough.manning_n = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(rough, 10.0).find("manning_n"), std::string::npos);
}

}  // namespace
}  // namespace canalid::core
