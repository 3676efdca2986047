#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/numerics/metrics.h"
#include "drivers/csv/csv_table.h"
#include "tests/support/run_program.h"

namespace canalid::testing {

/// Runs `canalid simulate` with the model file on the CSV it was identified from, then checks
/// that OUT.csv has time_s (the input's times) and y, and that the metrics recomputed here from
/// OUT.csv against the measured `output` column equal the model JSON's to 1e-9 relative (the
/// two simulations must be the same computation; only the JSON's 17-digit numbers separate them).
inline void ExpectSimulateReproducesModel(const std::filesystem::path& model_json,
                                          const std::filesystem::path& input_csv,
                                          const std::string& output,
                                          const std::filesystem::path& dir,
                                          const std::string& extra_args = "") {
  const auto out_csv = dir / (model_json.stem().string() + "_sim.csv");
  const ProgramRun run =
      RunProgram(CanalidProgram() + " simulate --model-json " + model_json.string() + " --input " +
                     input_csv.string() + " --out " + out_csv.string() + " " + extra_args,
                 dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json model = nlohmann::json::parse(ReadFile(model_json));
  const drivers::CsvTable in = drivers::CsvTable::Read(input_csv.string());
  const drivers::CsvTable sim = drivers::CsvTable::Read(out_csv.string());
  ASSERT_EQ(sim.columns(), (std::vector<std::string>{"time_s", "y"}));
  const Eigen::Index rows = sim.rows();
  ASSERT_GT(rows, 10);
  ASSERT_LE(rows, in.rows());
  EXPECT_EQ((sim.time_s() - in.time_s().tail(rows)).cwiseAbs().maxCoeff(), 0.0);
  const core::FitMetrics m =
      core::ComputeMetrics(in.Column(output).tail(rows), sim.Column("y"), in.sample_time_s());
  const nlohmann::json& expected = model.at("metrics");
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b) + 1e-300; };
  EXPECT_PRED2(near, m.rmse, expected.at("rmse").get<double>()) << model_json;
  EXPECT_PRED2(near, m.mae, expected.at("mae").get<double>()) << model_json;
  EXPECT_PRED2(near, m.fit_percent, expected.at("fit_percent").get<double>()) << model_json;
  EXPECT_PRED2(near, m.ise, expected.at("ise").get<double>()) << model_json;
  EXPECT_PRED2(near, m.norm_error, expected.at("norm_error").get<double>()) << model_json;
}

}  // namespace canalid::testing
