// Round trip through the real programs: `canalid identify` writes a model JSON, the plant built
// from it (sim/canalsim/model_plant_json.h) is driven sample by sample with an input record, and
// its output must equal `canalid simulate` of the same JSON on the same record.  The two share
// the model's equations but not their code: canalid simulate runs the batch simulators of core/
// (OpenLoop regressors times theta for id, core::Simulate for foptd, a fresh Oustaloup simulator
// for frac-foptd); the plants are streaming implementations in sim/.
#include "sim/canalsim/model_plant_json.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/fractional/fractional_foptd.h"
#include "drivers/csv/csv_table.h"
#include "tests/support/lpv_record.h"
#include "tests/support/run_program.h"

namespace canalid::sim {
namespace {

using canalid::testing::CanalidProgram;
using canalid::testing::kLpvA1;
using canalid::testing::kLpvB1;
using canalid::testing::LpvCsv;
using canalid::testing::ProgramRun;
using canalid::testing::Quadratic;
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
                                 const std::vector<std::string>& inputs,
                                 double relative_tolerance = 1e-9) {
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
    EXPECT_LE(worst, relative_tolerance * scale) << model["model"] << " worst " << worst;
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
  for (std::size_t t = 0; t < 500; ++t) {
    u1[t] = (rng() & 1U) ? 1.0 : -1.0;
    u2[t] = (rng() & 1U) ? 2.0 : 0.0;
    if (t >= 3) y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.8 * u1[t - 1] + 0.4 * u2[t - 3];
    y[t] += noise(rng);
    csv << static_cast<double>(t) * 5.0 << "," << u1[t] << "," << u2[t] << "," << y[t] << "\n";
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

// ---- soptd --------------------------------------------------------------------------------

// A soptd record as `canalid identify --model soptd` writes it (the keys the reader needs).
nlohmann::json SoptdJson(double gain, double t1_s, double t2_s, double delay_s, double input_offset,
                         double output_offset) {
  return {{"model", "soptd"},
          {"gain", gain},
          {"time_constants_s", {t1_s, t2_s}},
          {"delay_s", delay_s},
          {"input_offset", input_offset},
          {"output_offset", output_offset}};
}

// Unit step response of 1/((1 + T1 s)(1 + T2 s)) at t >= 0, distinct or equal poles.
double SecondOrderStep(double t1_s, double t2_s, double t_s) {
  if (t_s <= 0.0) return 0.0;
  if (t1_s == t2_s) return 1.0 - (1.0 + t_s / t1_s) * std::exp(-t_s / t1_s);
  return 1.0 - (t1_s * std::exp(-t_s / t1_s) - t2_s * std::exp(-t_s / t2_s)) / (t1_s - t2_s);
}

TEST(SoptdPlant, StepEqualsClosedFormAfterSubSampleDelay) {
  // K 0.8, T1 50 s, T2 12 s, tau 17.3 s = 8.65 samples of 2 s (the fraction exercises the
  // split-sample input), around an operating point: rest at u0 = 5 with input_offset 3 and
  // output_offset 1.5, so the level starts at 1.5 + 0.8 (5 - 3) = 3.1; +2 step at sample 10.
  // Equal poles (T1 = T2 = 30 s) use the (1 + t/T) e^{-t/T} form.
  for (const auto& [t1, t2] : {std::pair{50.0, 12.0}, std::pair{30.0, 30.0}}) {
    const double ts = 2.0, tau = 17.3, gain = 0.8;
    auto plant = PlantFromModelJson(SoptdJson(gain, t1, t2, tau, 3.0, 1.5), "soptd.json", ts,
                                    Eigen::VectorXd::Constant(1, 5.0));
    ASSERT_EQ(plant->input_count(), 1);
    double worst = 0.0;
    for (int k = 0; k < 400; ++k) {
      const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, k < 10 ? 5.0 : 7.0);
      const double expected = 3.1 + 2.0 * gain * SecondOrderStep(t1, t2, k * ts - 20.0 - tau);
      worst = std::max(worst, std::abs(plant->Output(u) - expected));
      plant->Advance(u);
    }
    // Exact ZOH: only the matrix exponential's rounding (1e-16) accumulates over 400 steps of a
    // stable system; 1e-12 m on a 1.6 m step would catch a wrong fraction or a one-sample shift
    // (those are of order 1e-2).
    EXPECT_LT(worst, 1e-12) << "T1 " << t1 << " T2 " << t2;
  }
}

// A second-order step record (K 1.5, T1 40 s, T2 9 s, tau 7.5 s, Ts 1 s) with seeded noise.
std::string SoptdStepCsv() {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::ostringstream csv;
  csv.precision(17);
  csv << "time_s,u,y\n";
  for (int k = 0; k < 600; ++k) {
    csv << k << "," << (k < 30 ? 2.0 : 3.0) << ","
        << 10.0 + 1.5 * SecondOrderStep(40.0, 9.0, k - 30.0 - 7.5) + noise(rng) << "\n";
  }
  return csv.str();
}

TEST_F(ModelPlantJson, SoptdPlantEqualsCanalidSimulate) {
  WriteFile(dir_ / "step.csv", SoptdStepCsv());
  const auto model = Identify((dir_ / "step.csv").string(), "--model soptd");
  ASSERT_EQ(model["model"], "soptd");
  ExpectPlantEqualsSimulate(model, (dir_ / "step.csv").string(), {"u"});
  // Another input at another sampling (a continuous model has none of its own).
  std::ostringstream other;
  other.precision(17);
  other << "time_s,u\n";
  for (int k = 0; k < 900; ++k) {
    other << k * 0.7 << "," << 2.5 + 0.7 * ((k / 53) % 3) - 1.1 * ((k / 29) % 2) << "\n";
  }
  WriteFile(dir_ / "other.csv", other.str());
  ExpectPlantEqualsSimulate(model, (dir_ / "other.csv").string(), {"u"});
}

// ---- frac-ss -------------------------------------------------------------------------------

// A frac-ss record in the form `canalid identify --model frac-ss` writes (companion A, B = a_n
// e_n, C = [1, c]).
nlohmann::json FracSsJson(int q, const std::vector<double>& a, const std::vector<double>& c,
                          int delay_samples, double ts, int memory_length, double input_offset,
                          double output_offset) {
  const std::size_t n = a.size();
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> row(n, 0.0);
    if (i + 1 < n) {
      row[i + 1] = 1.0;
    } else {
      for (std::size_t k = 0; k < n; ++k) row[k] = -a[n - 1 - k];
    }
    rows.push_back(row);
  }
  std::vector<double> b(n, 0.0);
  b.back() = a.back();
  std::vector<double> cc{1.0};
  cc.insert(cc.end(), c.begin(), c.end());
  return {{"model", "frac-ss"},
          {"q", q},
          {"alpha", 1.0 / q},
          {"A", rows},
          {"B", b},
          {"C", cc},
          {"delay_samples", delay_samples},
          {"delay_s", delay_samples * ts},
          {"sample_time_s", ts},
          {"memory_length", memory_length},
          {"input_offset", input_offset},
          {"output_offset", output_offset}};
}

TEST(CommensuratePlant, AlphaOneEqualsSampledSecondOrderStep) {
  // With q = 1 (alpha = 1) the GL difference is x[k+1] - x[k], so the model is the discrete
  // system x[k+1] = (I + A) x[k] + B u[k - nk] with transfer function
  //   z^-nk a2 (1 + c1 (z - 1)) / ((z - 1)^2 + a1 (z - 1) + a2).
  // Matching its poles to z_i = e^{-Ts/T_i} and its first step value to the continuous one makes
  // it the exact ZOH sampling of 1/((1 + T1 s)(1 + T2 s)) (the integer state space's matrix
  // exponential): a1 = 2 - z1 - z2, a2 = (1 - z1)(1 - z2) (unit gain), c1 = s(Ts) / a2.  Its step
  // response is then s(k Ts) of the closed form at every sample.
  const double t1 = 45.0, t2 = 11.0, ts = 3.0;
  const int nk = 4;
  const double z1 = std::exp(-ts / t1), z2 = std::exp(-ts / t2);
  const double a1 = 2.0 - z1 - z2, a2 = (1.0 - z1) * (1.0 - z2);
  const double c1 = SecondOrderStep(t1, t2, ts) / a2;
  // memory_length 0 (full, the history grows past its initial 1024 samples) and 3 (a ring);
  // for alpha = 1 the weights beyond w_1 are 0, so both must give the same closed form.
  for (const int memory : {0, 3}) {
    // Rest at u0 = 4 with input_offset 1 and output_offset 0.5: level 0.5 + (4 - 1) = 3.5
    // (unit static gain); +2.5 step at sample 20.
    auto plant = PlantFromModelJson(FracSsJson(1, {a1, a2}, {c1}, nk, ts, memory, 1.0, 0.5),
                                    "frac-ss.json", ts, Eigen::VectorXd::Constant(1, 4.0));
    double worst = 0.0;
    for (int k = 0; k < 3000; ++k) {
      const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, k < 20 ? 4.0 : 6.5);
      const double expected = 3.5 + 2.5 * SecondOrderStep(t1, t2, (k - 20 - nk) * ts);
      worst = std::max(worst, std::abs(plant->Output(u) - expected));
      plant->Advance(u);
    }
    // The recursion only rounds (poles 0.94 and 0.76, stable): 1e-11 on a 2.5 step; a delay off
    // by one sample would be about 0.06.
    EXPECT_LT(worst, 1e-11) << "memory " << memory;
  }
  // A frac-ss model is discrete: another sampling is refused.
  EXPECT_THROW(PlantFromModelJson(FracSsJson(1, {a1, a2}, {c1}, nk, ts, 0, 0.0, 0.0), "m.json", 1.0,
                                  Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
}

TEST_F(ModelPlantJson, FracSsPlantEqualsCanalidSimulateFullAndShortMemory) {
  // A half-order (q = 2) fit of the fractional step record (300 samples: the fit's simulations
  // are O(N^2)), then the plant against canalid simulate on another input, with the fit's full
  // memory and with a 40-sample short memory written into the record (canalid simulate honours
  // memory_length too).
  std::istringstream full(StepCsv());
  std::ostringstream head;
  std::string line;
  for (int i = 0; i <= 300 && std::getline(full, line); ++i) head << line << "\n";
  WriteFile(dir_ / "step.csv", head.str());
  std::istringstream other_full(OtherInputCsv());
  std::ostringstream other;
  for (int i = 0; i <= 400 && std::getline(other_full, line); ++i) other << line << "\n";
  WriteFile(dir_ / "other.csv", other.str());
  auto model = Identify((dir_ / "step.csv").string(), "--model frac-ss --q 2 --max-delay-s 6");
  ASSERT_EQ(model["model"], "frac-ss");
  ASSERT_EQ(model["q"], 2);
  // This fit is ill-conditioned (four states, poles near 1, long GL sums that cancel): scaling
  // its coefficients by 1 +- 1e-15 moves canalid simulate's own output on other.csv by 1.3e-7
  // (6.7e-8 with memory 40), so the order of summation alone separates the two by that much
  // (measured 3.5e-7 and 9.9e-8).  1e-8 of the output (about 70) is 7e-7; a wrong weight, a
  // memory term too many or a delay off by one sample are of order 1e-2.
  constexpr double kConditioning = 1e-8;
  ExpectPlantEqualsSimulate(model, (dir_ / "step.csv").string(), {"u"}, kConditioning);
  ExpectPlantEqualsSimulate(model, (dir_ / "other.csv").string(), {"u"}, kConditioning);
  model["memory_length"] = 40;
  ExpectPlantEqualsSimulate(model, (dir_ / "other.csv").string(), {"u"}, kConditioning);
}

// ---- lpv -----------------------------------------------------------------------------------

// Quadratic laws in theta: kLpvA1, kLpvB1 of tests/support/lpv_record.h, and a delay law.
constexpr double kLpvNk[3] = {0.5, 0.0, 1.9};  // 0.5 theta^2 + 1.9: 2.5 .. 3.9 on [1, 2]

nlohmann::json LpvJson(double input_offset, double output_offset) {
  auto list = [](const double(&p)[3]) { return std::vector<double>{p[0], p[1], p[2]}; };
  return {{"model", "lpv"},
          {"local_model", "arx"},
          {"kind", "first_order_arx"},
          {"schedule", "upstream"},
          {"inputs", {"gate"}},
          {"bands", {1.0, 1.2, 1.4, 1.6, 1.8, 2.0}},
          {"parameters", {"a1", "b1", "nk"}},
          {"degree", 2},
          {"coefficients", {{"a1", list(kLpvA1)}, {"b1", list(kLpvB1)}, {"nk", list(kLpvNk)}}},
          {"input_offset", input_offset},
          {"output_offset", output_offset},
          {"sample_time_s", 10.0}};
}

TEST(LpvArxPlant, FrozenScheduleEqualsLocalArxStep) {
  // At a constant theta the LPV model is the local ARX y[k] = -a1 y[k-1] + b1 du[k-nk] with the
  // parameters evaluated here from the laws; a step h of du at sample ks answers
  //   y[k] = b1 h (1 - (-a1)^(k - ks - nk + 1)) / (1 + a1),  k >= ks + nk  (0 before),
  // a closed form that is not the recursion.  nk rounds 0.5 theta^2 + 1.9 (3 at theta 1.1 and
  // 1.45, 4 at 1.9).
  for (const double theta : {1.1, 1.45, 1.9}) {
    const double a1 = Quadratic(kLpvA1, theta), b1 = Quadratic(kLpvB1, theta);
    const long nk = std::lround(Quadratic(kLpvNk, theta));
    auto plant =
        PlantFromModelJson(LpvJson(2.0, 0.7), "lpv.json", 10.0, Eigen::VectorXd::Constant(1, 2.0));
    ASSERT_EQ(plant->input_count(), 2);
    const int ks = 6;
    const double h = 1.5;
    double worst = 0.0;
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector2d u(k < ks ? 2.0 : 2.0 + h, theta);
      const long m = k - ks - nk + 1;
      const double expected =
          0.7 +
          (m >= 1 ? b1 * h * (1.0 - std::pow(-a1, static_cast<double>(m))) / (1.0 + a1) : 0.0);
      worst = std::max(worst, std::abs(plant->Output(u) - expected));
      plant->Advance(u);
    }
    // Rounding only (|a1| < 1): 1e-13 against a response of about 0.3.
    EXPECT_LT(worst, 1e-13) << "theta " << theta;
  }
}

TEST(LpvArxPlant, RefusesDelaysBeyondItsRingAndOtherLocals) {
  // The ring covers the bands [1, 2] widened by their span, theta in [0, 3]: nk up to
  // round(0.5 * 9 + 1.9) = 6.  theta = 5 asks for 14 samples.
  auto plant =
      PlantFromModelJson(LpvJson(0.0, 0.0), "lpv.json", 10.0, Eigen::VectorXd::Constant(1, 0.0));
  plant->Advance(Eigen::Vector2d(1.0, 3.0));
  EXPECT_NO_THROW(plant->Output(Eigen::Vector2d(1.0, 3.0)));
  EXPECT_THROW(plant->Output(Eigen::Vector2d(1.0, 5.0)), std::invalid_argument);
  EXPECT_THROW(plant->Output(Eigen::VectorXd::Zero(1)), std::invalid_argument);
  nlohmann::json other = LpvJson(0.0, 0.0);
  other["local_model"] = "frac-foptd";
  other["kind"] = "frac_foptd";
  EXPECT_THROW(PlantFromModelJson(other, "m.json", 10.0, Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
  // A discrete model: another sampling is refused.
  EXPECT_THROW(PlantFromModelJson(LpvJson(0.0, 0.0), "m.json", 5.0, Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
  // Bands missing or not numbers, and a delay law no ring could hold.
  for (const nlohmann::json& bands : {nlohmann::json(), nlohmann::json({1.0, "x"})}) {
    nlohmann::json broken = LpvJson(0.0, 0.0);
    if (bands.is_null()) {
      broken.erase("bands");
    } else {
      broken["bands"] = bands;
    }
    EXPECT_THROW(PlantFromModelJson(broken, "m.json", 10.0, Eigen::VectorXd::Zero(1)),
                 std::invalid_argument)
        << bands;
  }
  nlohmann::json long_delay = LpvJson(0.0, 0.0);
  long_delay["coefficients"]["nk"] = {0.0, 0.0, 1e9};
  EXPECT_THROW(PlantFromModelJson(long_delay, "m.json", 10.0, Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
}

TEST_F(ModelPlantJson, LpvPlantEqualsCanalidSimulate) {
  // The support record with seed 2 and noise 0.01 N(0, 0.01).
  WriteFile(dir_ / "lpv.csv", LpvCsv(2, 0.01, 0.01));
  const auto model =
      Identify((dir_ / "lpv.csv").string(),
               "--model lpv --local arx --u gate --y level --schedule upstream --bands "
               "1.0,1.2,1.4,1.6,1.8,2.0");
  ASSERT_EQ(model["model"], "lpv");
  ExpectPlantEqualsSimulate(model, (dir_ / "lpv.csv").string(), {"gate", "upstream"});
  // The hand-written laws (nk varies with theta) on the same record.
  ExpectPlantEqualsSimulate(LpvJson(0.1, -0.3), (dir_ / "lpv.csv").string(), {"gate", "upstream"});
}

TEST_F(ModelPlantJson, RejectsKindsWithoutPlantAndWrongSampling) {
  const nlohmann::json magic = {{"model", "magic"}};
  EXPECT_THROW(PlantFromModelJson(magic, "m.json", 1.0, Eigen::VectorXd::Zero(1)),
               std::invalid_argument);
  const std::string csv = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";
  const auto model = Identify(csv, "--model id --max-delay-s 3600");
  // The record is sampled every 60 s; nk means nothing at 30 s.
  EXPECT_THROW(PlantFromModelJson(model, "m.json", 30.0, Eigen::VectorXd::Constant(1, 10.0)),
               std::invalid_argument);
  // The daemon's batch arx models deviations from a rest point: refused by name, not run as if
  // its offsets were 0.
  const nlohmann::json deviations = {{"model", "arx"},      {"na", 1},
                                     {"nb", {1}},           {"nk", {1}},
                                     {"a", {-0.9}},         {"b_coeffs", {{0.1}}},
                                     {"input_offset", 0.5}, {"output_offset", 2.0}};
  try {
    PlantFromModelJson(deviations, "m.json", 1.0, Eigen::VectorXd::Zero(1));
    ADD_FAILURE() << "an arx model with offsets was accepted as a plant";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("m.json: input_offset/output_offset"), std::string::npos)
        << e.what();
  }
}

TEST(FractionalFoptdPlant, HandWrittenMinimalModelFollowsTheMittagLefflerStep) {
  // The paper's keys only: offsets 0, and the band the fit chooses for 1000 samples (the plant
  // does not know its run's length).  A unit step at sample 20, checked to 1000 s (4000 samples,
  // well past the band's horizon) against the exact step response; 0.1 % of K, the default
  // band's error inside the flume paper's alpha range (core/fractional/fractional_simulator.h).
  const nlohmann::json model = {{"model", "frac-foptd"},
                                {"gain", 0.372},
                                {"time_constant_s", 10.975},
                                {"alpha", 0.8},
                                {"delay_s", 0.0}};
  const double ts = 0.25;
  auto plant = PlantFromModelJson(model, "paper.json", ts, Eigen::VectorXd::Zero(1));
  const core::FractionalFoptdParams truth{0.372, 10.975, 0.8, 0.0};
  double worst = 0.0;
  for (int k = 0; k <= 4020; ++k) {
    const Eigen::VectorXd u = Eigen::VectorXd::Constant(1, k < 20 ? 0.0 : 1.0);
    worst = std::max(worst, std::abs(plant->Output(u) -
                                     core::FractionalFoptdStepResponse(truth, (k - 20) * ts)));
    plant->Advance(u);
  }
  EXPECT_LT(worst, 0.001 * 0.372);
}

TEST(IntegratorDelayLevelPlant, HandWrittenModelWithoutSampleTimeRunsAtThePlants) {
  // b and nk only: p21, offset and drift 0, the plant's sample time.  Inflow 1 m3/s above the
  // outflow from sample 0: the level rises by b per sample once the 2-sample delay has passed.
  const nlohmann::json model = {{"model", "id"}, {"b", 0.002}, {"nk", 2}};
  auto plant = PlantFromModelJson(model, "paper.json", 30.0, Eigen::Vector2d(10.0, 10.0));
  EXPECT_EQ(plant->sample_time_s(), 30.0);
  std::vector<double> y;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector2d u(11.0, 10.0);
    y.push_back(plant->Output(u));
    plant->Advance(u);
  }
  EXPECT_NEAR(y[7] - y[6], 0.002, 1e-12);
  EXPECT_NEAR(y[6] - y[5], 0.002, 1e-12);
}

}  // namespace
}  // namespace canalid::sim
