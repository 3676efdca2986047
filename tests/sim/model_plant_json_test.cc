// Round trip through the real programs: `canalid identify` writes a model JSON, the plant built
// from it (sim/model_json) is driven sample by sample with an input record, and its output must
// equal `canalid simulate` of the same JSON on the same record.  The two share the model's
// equations but not their code: canalid simulate runs the batch simulators of core/ (OpenLoop
// regressors times theta for id, core::Simulate for foptd, a fresh Oustaloup simulator for
// frac-foptd); the plants are streaming implementations in sim/.
#include "sim/model_json/model_plant_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/fractional_foptd.h"
#include "drivers/csv/csv_table.h"
#include "support/run_program.h"

namespace canalid::sim {
namespace {

using canalid::testing::CanalidProgram;
using canalid::testing::ProgramRun;
using canalid::testing::ReadFile;
using canalid::testing::RunProgram;
using canalid::testing::TestDirectory;
using canalid::testing::WriteFile;

// A gate step through a fractional plant (K 0.5, T 6 s^alpha, alpha 0.7, tau 3 s) with seeded
// noise: something for identify to fit.
std::string StepCsv() {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.1);
  const core::FractionalFoptdParams truth{0.5, 6.0, 0.7, 3.0};
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u,y\n";
  for (int k = 0; k < 2000; ++k) {
    const double t = k * 0.15;
    csv << t << "," << (k < 20 ? 20.0 : 45.0) << ","
        << 60.0 + 25.0 * core::FractionalFoptdStepResponse(truth, t - 3.0) + noise(rng) << "\n";
  }
  return csv.str();
}

// Another input: a deterministic square-ish sequence that starts away from the fit's offset.
std::string OtherInputCsv() {
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u\n";
  for (int k = 0; k < 1500; ++k) {
    csv << k * 0.15 << "," << 30.0 + 8.0 * ((k / 97) % 3) - 5.0 * ((k / 41) % 2) << "\n";
  }
  return csv.str();
}

class ModelPlantJson : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TestDirectory(std::string("plant-") +
                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  nlohmann::json Identify(const std::string& csv, const std::string& args) {
    const ProgramRun run =
        RunProgram(CanalidProgram() + " identify " + args + " --input " + csv, dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return nlohmann::json::parse(run.out);
  }
  // canalid simulate's output (rows first_row..N-1) against the plant fed every row.
  void ExpectPlantEqualsSimulate(const nlohmann::json& model, const std::string& csv,
                                 const std::vector<std::string>& inputs) {
    const auto json_path = dir_ / "model.json";
    WriteFile(json_path, model.dump());
    const auto out = dir_ / "simulated.csv";
    const ProgramRun run =
        RunProgram(CanalidProgram() + " simulate --model-json " + json_path.string() + " --input " +
                       csv + " --out " + out.string(),
                   dir_);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto report = nlohmann::json::parse(run.out);
    const int first_row = report["first_row"].get<int>();
    const Eigen::VectorXd simulated = drivers::CsvTable::Read(out.string()).Column("y");

    const drivers::CsvTable table = drivers::CsvTable::Read(csv);
    Eigen::MatrixXd u(table.rows(), static_cast<Eigen::Index>(inputs.size()));
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      u.col(static_cast<Eigen::Index>(i)) = table.Column(inputs[i]);
    }
    const Eigen::VectorXd first = u.row(0).transpose();
    // arx starts from the measured outputs before first_row, as canalid simulate does.
    const Eigen::VectorXd initial_outputs = model["model"] == "arx"
                                                ? Eigen::VectorXd(table.Column("y").head(first_row))
                                                : Eigen::VectorXd();
    auto plant =
        PlantFromModelJson(model, "model.json", table.sample_time_s(), first, initial_outputs);
    ASSERT_EQ(simulated.size(), table.rows() - first_row);
    double worst = 0.0;
    for (Eigen::Index k = 0; k < table.rows(); ++k) {
      const Eigen::VectorXd uk = u.row(k).transpose();
      if (k >= first_row) {
        worst = std::max(worst, std::abs(plant->Output(uk) - simulated(k - first_row)));
      }
      plant->Advance(uk);
    }
    // The same arithmetic in another order (running sums against a regression product, one
    // state-space step at a time against a batch): equal to rounding, and the CSV keeps 17 digits.
    const double scale = simulated.cwiseAbs().maxCoeff();
    EXPECT_LE(worst, 1e-9 * scale) << model["model"] << " worst " << worst;
  }
  std::filesystem::path dir_;
};

TEST_F(ModelPlantJson, IdPlantEqualsCanalidSimulateOnSaintVenantRecord) {
  const std::string csv = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";
  const auto model = Identify(csv, "--model id --max-delay-s 3600");
  ASSERT_EQ(model["model"], "id");
  ExpectPlantEqualsSimulate(model, csv, {"q_in", "q_out"});
  // Also on the noisy record's model (drift and offset terms non-zero).
  const std::string noisy =
      std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs-noisy.csv";
  ExpectPlantEqualsSimulate(Identify(noisy, "--model id --max-delay-s 3600"), csv,
                            {"q_in", "q_out"});
}

TEST_F(ModelPlantJson, FoptdAndFractionalPlantsEqualCanalidSimulateOnAnotherInput) {
  WriteFile(dir_ / "step.csv", StepCsv());
  WriteFile(dir_ / "other.csv", OtherInputCsv());
  for (const std::string kind : {"foptd", "frac-foptd"}) {
    const auto model = Identify((dir_ / "step.csv").string(), "--model " + kind);
    ASSERT_EQ(model["model"], kind);
    ExpectPlantEqualsSimulate(model, (dir_ / "other.csv").string(), {"u"});
    ExpectPlantEqualsSimulate(model, (dir_ / "step.csv").string(), {"u"});
  }
}

// Two inputs through y(t) = 1.2 y(t-1) - 0.5 y(t-2) + 0.8 u1(t-1) + 0.4 u2(t-3) + noise.
std::string ArxCsv() {
  std::mt19937 rng(23);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u1,u2,y\n";
  std::vector<double> u1(500), u2(500), y(500, 0.0);
  for (int t = 0; t < 500; ++t) {
    u1[t] = (rng() & 1U) ? 1.0 : -1.0;
    u2[t] = (rng() & 1U) ? 2.0 : 0.0;
    if (t >= 3) y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u1[t - 1] + 0.4 * u2[t - 3];
    y[t] += noise(rng);
    csv << t * 5.0 << "," << u1[t] << "," << u2[t] << "," << y[t] << "\n";
  }
  return csv.str();
}

TEST_F(ModelPlantJson, ArxPlantEqualsCanalidSimulate) {
  WriteFile(dir_ / "arx.csv", ArxCsv());
  const auto model =
      Identify((dir_ / "arx.csv").string(), "--model arx --u u1,u2 --y y --na 2 --nb 1,1 --nk 1,3");
  ASSERT_EQ(model["model"], "arx");
  ExpectPlantEqualsSimulate(model, (dir_ / "arx.csv").string(), {"u1", "u2"});
}

TEST_F(ModelPlantJson, RejectsKindsWithoutPlantAndWrongSampling) {
  const nlohmann::json soptd = {{"model", "soptd"}};
  EXPECT_THROW(PlantFromModelJson(soptd, "m.json", 1.0, Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
  const std::string csv = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";
  const auto model = Identify(csv, "--model id --max-delay-s 3600");
  // The record is sampled every 60 s; nk means nothing at 30 s.
  EXPECT_THROW(PlantFromModelJson(model, "m.json", 30.0, Eigen::VectorXd::Constant(1, 10.0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace canalid::sim
