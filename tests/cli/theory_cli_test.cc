// `canalid theory` run as a user runs it: the IDZ model of every ASCE pool from canalsim's canal
// files, checked against the published table (Litrico & Fromion 2004), its Bode CSV against the
// model's closed forms, and its errors.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

struct Published {
  double flow, delay, area, p21, p22;
};

// (canal, regime, pool) -> the table's row.
std::map<std::string, Published> PublishedTable() {
  std::ifstream in(std::string(CANALID_REFERENCE_DIR) + "/asce_idz_litrico_fromion_2004.csv");
  std::map<std::string, Published> table;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string canal, regime, pool, field;
    std::getline(ss, canal, ',');
    std::getline(ss, regime, ',');
    std::getline(ss, pool, ',');
    Published p{};
    double* values[] = {&p.flow, &p.delay, &p.area, &p.p21, &p.p22};
    for (double* v : values) {
      std::getline(ss, field, ',');
      *v = std::stod(field);
    }
    std::string key = canal;
    key.append("/").append(regime).append("/").append(pool);
    table[key] = p;
  }
  return table;
}

void ExpectPublished(const nlohmann::json& pool, const Published& want, const std::string& where) {
  EXPECT_NEAR(pool.at("flow_m3s").get<double>(), want.flow, 1e-9) << where;
  EXPECT_NEAR(pool.at("delay_s").get<double>() / want.delay, 1.0, 0.02) << where;
  EXPECT_NEAR(pool.at("area_m2").get<double>() / want.area, 1.0, 0.02) << where;
  EXPECT_NEAR(pool.at("p21_s_per_m2").get<double>() / want.p21, 1.0, 0.05) << where;
  EXPECT_NEAR(pool.at("p22_s_per_m2").get<double>() / want.p22, 1.0, 0.05) << where;
}

std::string Canal(int number) {
  return std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal" + std::to_string(number) +
         ".toml";
}

// Both canal files hold the "high" flows; --all uses each pool's flow at the steady state.
TEST(TheoryCli, AllPoolsOfBothCanalsMatchThePublishedHighFlowTable) {
  const auto table = PublishedTable();
  ASSERT_EQ(table.size(), 32u);
  for (int canal : {1, 2}) {
    const auto dir = TestDirectory("theory_all_" + std::to_string(canal));
    const ProgramRun run =
        RunProgram(CanalidProgram() + " theory --all --canal " + Canal(canal), dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto json = nlohmann::json::parse(run.out);
    ASSERT_EQ(json.at("pools").size(), 8u);
    for (const auto& pool : json.at("pools")) {
      const std::string key = std::to_string(canal) + "/high/" + pool.at("pool").get<std::string>();
      ExpectPublished(pool, table.at(key), key);
    }
  }
}

// The low-flow rows: one pool at a time, with --flow.
TEST(TheoryCli, OnePoolAtAGivenFlowMatchesThePublishedLowFlowTable) {
  const auto table = PublishedTable();
  for (int canal : {1, 2}) {
    for (int pool = 1; pool <= 8; ++pool) {
      const std::string key = std::to_string(canal) + "/low/" + std::to_string(pool);
      const auto dir = TestDirectory("theory_low");
      std::ostringstream flow;
      flow.precision(17);
      flow << table.at(key).flow;
      const ProgramRun run =
          RunProgram(CanalidProgram() + " theory --canal " + Canal(canal) + " --pool " +
                         std::to_string(pool) + " --flow " + flow.str(),
                     dir);
      ASSERT_EQ(run.exit_code, 0) << key << ": " << run.err;
      ExpectPublished(nlohmann::json::parse(run.out), table.at(key), key);
    }
  }
}

// The Bode CSV is the model's frequency response: an integrator 1/(A w) at low frequencies, the
// direct gains at high frequencies, and p21's phase falling with the delay.
TEST(TheoryCli, BodeCsvFollowsTheModel) {
  const auto dir = TestDirectory("theory_bode");
  const auto csv = dir / "bode.csv";
  const ProgramRun run = RunProgram(CanalidProgram() + " theory --canal " + Canal(2) +
                                        " --pool 2 --bode " + csv.string() + " --bode-points 50",
                                    dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto model = nlohmann::json::parse(run.out);
  const double area = model.at("area_m2"), delay = model.at("delay_s");
  const double p21 = model.at("p21_s_per_m2"), p22 = model.at("p22_s_per_m2");
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line,
            "pool_index,omega_rad_s,p21_gain_s_per_m2,p21_phase_deg,p22_gain_s_per_m2,"
            "p22_phase_deg");
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<double> row;
    std::string field;
    while (std::getline(ss, field, ',')) row.push_back(std::stod(field));
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 50u);
  const auto& first = rows.front();
  const auto& last = rows.back();
  EXPECT_NEAR(first[1], 0.01 / delay, 1e-9 * first[1]);
  EXPECT_NEAR(last[1], 100.0 / delay, 1e-9 * last[1]);
  EXPECT_NEAR(first[2] * area * first[1], 1.0, 0.01);  // |p21| ~ 1/(A w)
  EXPECT_NEAR(first[4] * area * first[1], 1.0, 0.01);
  EXPECT_NEAR(last[2] / p21, 1.0, 0.01);  // |p21| -> p21
  EXPECT_NEAR(last[4] / p22, 1.0, 0.01);
  // Unwrapped: the delay's phase -w tau (degrees) plus the zero's, which tends to 0.
  EXPECT_NEAR(last[3], -last[1] * delay * 180.0 / std::numbers::pi, 5.0);
  EXPECT_NEAR(last[5], 180.0, 5.0);  // p22 = -(p22 + 1/(A s)) -> -p22
}

TEST(TheoryCli, BadInputIsNamedAndExitsTwo) {
  const auto dir = TestDirectory("theory_errors");
  auto run = [&](const std::string& args) {
    return RunProgram(CanalidProgram() + " theory " + args, dir);
  };
  ProgramRun r = run("--canal " + Canal(2) + " --pool 9");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--pool '9' is not a pool of"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pools: 1, 2, 3, 4, 5, 6, 7, 8"), std::string::npos) << r.err;
  r = run("--canal " + Canal(2));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("give --pool NAME or --all"), std::string::npos) << r.err;
  r = run("--canal " + Canal(2) + " --pool 2 --flow 200");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("pool 2 at 200 m3/s: flow 200 m3/s is not subcritical"), std::string::npos)
      << r.err;
  r = run("--canal " + Canal(2) + " --pool 2 --flow -3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
  r = run("--canal " + Canal(2) + " --all --flow 3");
  EXPECT_EQ(r.exit_code, 2);
  r = run("--canal " + Canal(2) + " --pool 2 --bode-min-rad-s 0.001");  // does nothing alone
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--bode-min-rad-s requires --bode"), std::string::npos) << r.err;
  const auto bad = dir / "bad.toml";
  WriteFile(bad,
            "name = \"x\"\n[upstream]\ntype = \"flow\"\nflow_m3s = 1.0\n[[pool]]\nname = \"1\"\n"
            "length_m = -5.0\n");
  r = run("--canal " + bad.string() + " --all");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.toml"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

}  // namespace
}  // namespace canalid::testing
