#include "daemon/canalid/report_analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/fractional/lpv_model.h"
#include "core/linear/correlation.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/simulate_command.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json_read.h"

namespace canalid::cli {
namespace {

constexpr int kLpvGridPoints = 200;

// A record of the model's inputs held at their first values (the schedule, for lpv, at theta),
// with the first input raised by one unit from row `step_row` on (never when step_row < 0).
drivers::CsvTable StepTable(const nlohmann::json& model, const drivers::CsvTable& table,
                            const std::vector<std::string>& inputs, double theta,
                            Eigen::Index step_row) {
  const Eigen::Index n = table.rows();
  std::vector<std::string> names = {"time_s"};
  std::vector<Eigen::VectorXd> columns = {table.time_s()};
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    Eigen::VectorXd u = Eigen::VectorXd::Constant(n, RequireColumn(table, inputs[i])(0));
    if (i == 0 && step_row >= 0) u.tail(n - step_row).array() += 1.0;
    names.push_back(inputs[i]);
    columns.push_back(u);
  }
  // ARX starts from the measured output: hold it too, so both records start alike.
  const std::string output = model.value("output", std::string());
  if (!output.empty() && table.HasColumn(output)) {
    names.push_back(output);
    columns.push_back(Eigen::VectorXd::Constant(n, table.Column(output)(0)));
  }
  const std::string schedule = model.value("schedule", std::string());
  if (!schedule.empty()) {
    names.push_back(schedule);
    columns.push_back(Eigen::VectorXd::Constant(n, theta));
  }
  try {
    return drivers::CsvTable::FromColumns("step response", names, columns);
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
}

// The response to a unit step as the difference of two simulations, with and without the step,
// so offsets, drifts and initial conditions of every kind cancel (all kinds are linear in u).
StepCurve StepResponse(const std::string& label, const nlohmann::json& model,
                       const drivers::CsvTable& table, double theta) {
  const std::string source = label + " model";
  const std::vector<std::string> inputs = drivers::ModelInputs(model, source);
  if (inputs.empty()) throw InputError(source + ": no input columns");
  const SimulatedOutput rest =
      SimulateModel(model, source, StepTable(model, table, inputs, theta, -1), {});
  // Continuous kinds take u - u[0]: a step at row 0 would vanish.
  const Eigen::Index step_row = std::max<Eigen::Index>(rest.first_row, 1);
  const SimulatedOutput stepped =
      SimulateModel(model, source, StepTable(model, table, inputs, theta, step_row), {});
  const Eigen::Index skip = step_row - rest.first_row;
  const Eigen::Index n = rest.y.size() - skip;
  StepCurve curve;
  curve.label = label + " (" + inputs.front() + ")";
  curve.response = stepped.y.tail(n) - rest.y.tail(n);
  curve.time_s =
      Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * table.sample_time_s();
  return curve;
}

LpvCurves LpvParameterCurves(const nlohmann::json& model, const std::string& source) {
  const drivers::LpvRecord record = drivers::LpvFromJson(model, source);
  LpvCurves curves;
  curves.schedule = record.schedule;
  curves.parameters = record.model.parameter_names;
  curves.band_edges = model.at("bands").get<std::vector<double>>();
  const auto p = static_cast<Eigen::Index>(curves.parameters.size());
  curves.theta_grid = Eigen::VectorXd::LinSpaced(kLpvGridPoints, curves.band_edges.front(),
                                                 curves.band_edges.back());
  curves.polynomial.resize(kLpvGridPoints, p);
  for (Eigen::Index i = 0; i < kLpvGridPoints; ++i) {
    curves.polynomial.row(i) = record.model.Evaluate(curves.theta_grid(i)).transpose();
  }
  const nlohmann::json& bands = model.at("metrics_per_band");
  curves.theta_points.resize(static_cast<Eigen::Index>(bands.size()));
  curves.local.resize(static_cast<Eigen::Index>(bands.size()), p);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    const auto row = static_cast<Eigen::Index>(b);
    curves.theta_points(row) = bands[b].at("theta_mean").get<double>();
    for (Eigen::Index j = 0; j < p; ++j) {
      curves.local(row, j) =
          bands[b].at("local_params").at(curves.parameters[static_cast<std::size_t>(j)]);
    }
  }
  return curves;
}

void Simulate(ModelAnalysis& a, const drivers::CsvTable& table) {
  const SimulatedOutput sim = SimulateModel(a.model, a.kind + " model", table, {});
  a.notes.insert(a.notes.end(), sim.warnings.begin(), sim.warnings.end());
  const Eigen::Index n = sim.y.size();
  a.output = a.model.value("output", std::string());
  a.time_s = table.time_s().tail(n);
  a.measured = RequireColumn(table, a.output).tail(n);
  a.simulated = sim.y;
  a.residual = a.measured - a.simulated;
  const int lags = static_cast<int>(std::min<Eigen::Index>(kResidualLags, n - 1));
  try {
    a.autocorrelation = core::CrossCorrelation(a.residual, a.residual, lags);
    a.band_99 = core::TwoSidedNormalQuantile(0.99) / std::sqrt(static_cast<double>(n));
  } catch (const std::invalid_argument& e) {
    a.notes.push_back(std::string("no residual autocorrelation: ") + e.what());
  }
}

}  // namespace

ModelAnalysis AnalyseModel(const std::string& kind, const nlohmann::json& model,
                           const drivers::CsvTable& table) {
  ModelAnalysis a;
  a.kind = kind;
  a.model = model;
  if (model.contains("warnings") && model.at("warnings").is_array()) {
    for (const auto& w : model.at("warnings")) {
      if (w.is_string()) a.notes.push_back("identify: " + w.get<std::string>());
    }
  }
  const bool lpv_without_simulation = kind == "lpv" && model.value("kind", "") != "first_order_arx";
  if (lpv_without_simulation) {
    a.notes.push_back("lpv with " + model.value("local_model", std::string("?")) +
                      " locals: no simulation along the scheduling trajectory (arx locals only), "
                      "so no fit, residual or step plots");
  } else {
    Simulate(a, table);
  }
  try {
    if (kind == "lpv") {
      a.has_lpv = true;
      a.lpv = LpvParameterCurves(model, kind + " model");
      if (!lpv_without_simulation) {
        for (Eigen::Index i = 0; i < a.lpv.theta_points.size(); ++i) {
          char theta[32];
          std::snprintf(theta, sizeof theta, "%.4g", a.lpv.theta_points(i));
          a.steps.push_back(StepResponse("lpv at " + a.lpv.schedule + " = " + theta, model, table,
                                         a.lpv.theta_points(i)));
        }
      }
    } else {
      a.steps.push_back(StepResponse(kind, model, table, 0.0));
    }
  } catch (const drivers::ModelJsonError& e) {
    throw InputError(e.what());
  }
  return a;
}

}  // namespace canalid::cli
