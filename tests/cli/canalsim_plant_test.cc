// `canalsim plant`: the plant of a model JSON (sim/canalsim/model_plant_json.h) driven by a CSV
// from the command line.  Its output must equal `canalid simulate` of the same JSON on the same
// CSV (the two share the models' equations but not their code: batch simulators in core/ against
// the streaming plants of sim/), for a kind of each family, and its errors are one line with
// exit 78.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/csv/csv_table.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

std::string CanalsimProgram() { return std::string(CANALID_BINARY_DIR) + "/sim/canalsim"; }

class CanalsimPlant : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TestDirectory(std::string("canalsim-plant-") +
                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  // canalsim plant and canalid simulate on the same files; compares the rows simulate writes
  // (it starts at first_row for id and arx) with the same rows of canalsim's output.
  void ExpectEqualToSimulate(const nlohmann::json& model, const std::string& csv,
                             const std::string& extra = "") {
    const auto json_path = dir_ / "model.json";
    WriteFile(json_path, model.dump());
    const auto plant_out = dir_ / "plant.csv";
    const ProgramRun plant =
        RunProgram(CanalsimProgram() + " plant --model-json " + json_path.string() + " --input " +
                       csv + " --out " + plant_out.string() + " --column level " + extra,
                   dir_);
    ASSERT_EQ(plant.exit_code, 0) << plant.err;
    const auto simulate_out = dir_ / "simulated.csv";
    const ProgramRun simulate =
        RunProgram(CanalidProgram() + " simulate --model-json " + json_path.string() + " --input " +
                       csv + " --out " + simulate_out.string() + " " + extra,
                   dir_);
    ASSERT_EQ(simulate.exit_code, 0) << simulate.err;
    const drivers::CsvTable a = drivers::CsvTable::Read(plant_out.string());
    const drivers::CsvTable b = drivers::CsvTable::Read(simulate_out.string());
    const drivers::CsvTable in = drivers::CsvTable::Read(csv);
    ASSERT_EQ(a.columns(), (std::vector<std::string>{"time_s", "level"}));
    ASSERT_EQ(a.rows(), in.rows());
    EXPECT_EQ((a.time_s() - in.time_s()).cwiseAbs().maxCoeff(), 0.0);
    const Eigen::VectorXd y = b.Column("y");
    const Eigen::VectorXd level = a.Column("level").tail(y.size());
    // Rounding only (both CSVs keep 17 digits); a wrong convention (offset, start, delay) moves
    // the output by a visible fraction of its range.
    EXPECT_LE((level - y).cwiseAbs().maxCoeff(), 1e-9 * y.cwiseAbs().maxCoeff()) << model["model"];
  }
  std::filesystem::path dir_;
};

TEST_F(CanalsimPlant, HelpListsEveryKind) {
  const ProgramRun run = RunProgram(CanalsimProgram() + " plant --help", dir_);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_NE(run.out.find("id, idz, arx, foptd, soptd, frac-foptd, frac-ss, lpv"), std::string::npos)
      << run.out;
}

TEST_F(CanalsimPlant, SoptdIdAndLpvEqualCanalidSimulate) {
  // soptd: hand-written, around an operating point the input does not start at.
  const nlohmann::json soptd = {
      {"model", "soptd"}, {"gain", 0.4},         {"time_constants_s", {900.0, 240.0}},
      {"delay_s", 610.0}, {"input_offset", 9.0}, {"output_offset", 2.0}};
  const std::string prbs = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";
  ExpectEqualToSimulate(soptd, prbs, "--u q_in");
  // id: identified by canalid from the Saint-Venant record.
  const ProgramRun id = RunProgram(
      CanalidProgram() + " identify --model id --max-delay-s 3600 --input " + prbs, dir_);
  ASSERT_EQ(id.exit_code, 0) << id.err;
  ExpectEqualToSimulate(nlohmann::json::parse(id.out), prbs);
  // idz: with p22 from the geometry's prior (pool 2 ends at a fixed gate), so the outflow's
  // direct term is in the output.
  const ProgramRun idz = RunProgram(
      CanalidProgram() + " identify --model idz --max-delay-s 3600 --canal " + CANALID_SOURCE_DIR +
          "/config/sim/asce-canal2.toml" + " --pool 2 --input " + prbs,
      dir_);
  ASSERT_EQ(idz.exit_code, 0) << idz.err;
  const nlohmann::json idz_model = nlohmann::json::parse(idz.out);
  ASSERT_GT(idz_model.value("p22_s_per_m2", 0.0), 0.0) << idz.out;
  ExpectEqualToSimulate(idz_model, prbs);
  // lpv: input q_in, scheduled by the downstream level (its own delay law in theta).
  const nlohmann::json lpv = {
      {"model", "lpv"},
      {"local_model", "arx"},
      {"kind", "first_order_arx"},
      {"schedule", "level"},
      {"inputs", {"q_in"}},
      {"bands", {1.9, 2.0, 2.1, 2.2}},
      {"parameters", {"a1", "b1", "nk"}},
      {"degree", 1},
      {"coefficients", {{"a1", {0.3, -1.55}}, {"b1", {0.0, 0.02}}, {"nk", {20.0, -30.0}}}},
      {"input_offset", 10.0},
      {"output_offset", 2.1},
      {"sample_time_s", 60.0}};
  ExpectEqualToSimulate(lpv, prbs);
}

TEST_F(CanalsimPlant, BadModelIsOneLineAndExit78) {
  WriteFile(dir_ / "bad.json", R"({"model": "soptd", "gain": 1.0})");
  const std::string prbs = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";
  const ProgramRun run =
      RunProgram(CanalsimProgram() + " plant --model-json " + (dir_ / "bad.json").string() +
                     " --input " + prbs + " --out " + (dir_ / "o.csv").string() + " --u q_in",
                 dir_);
  EXPECT_EQ(run.exit_code, 78);
  EXPECT_NE(run.err.find("bad.json: key 'time_constants_s'"), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

}  // namespace
}  // namespace canalid::testing
