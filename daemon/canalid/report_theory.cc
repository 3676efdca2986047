#include "daemon/canalid/report_theory.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/hydraulics/idz_model.h"
#include "daemon/canalid/pool_theory.h"
#include "daemon/canalid/table_columns.h"

namespace canalid::cli {
namespace {

constexpr int kBodePoints = 200;

BodeCurve Bode(const std::string& label, const core::IdzModel& model,
               const Eigen::VectorXd& omega) {
  BodeCurve curve;
  curve.label = label;
  curve.omega_rad_s = omega;
  curve.gain.resize(omega.size());
  curve.phase_deg.resize(omega.size());
  for (Eigen::Index i = 0; i < omega.size(); ++i) {
    curve.gain(i) = std::abs(core::IdzDownstreamFromInflow(model, omega(i)));
    curve.phase_deg(i) =
        core::IdzDownstreamFromInflowPhase(model, omega(i)) * 180.0 / std::numbers::pi;
  }
  return curve;
}

}  // namespace

void AddIdzTheory(ModelAnalysis& idz, const IdentifyOptions& options,
                  const drivers::CsvTable& table) {
  if (options.canal.empty() || idz.kind != "idz") return;
  const double flow = RequireColumn(table, options.qin).mean();
  const core::IdzModel theory = PoolTheory(options.canal, options.pool, flow).model;
  const std::string label = "idz from the geometry (pool " + options.pool + ")";

  // Step: on the identified curve's time grid, or a grid of its own.
  StepCurve step;
  step.label = label;
  step.time_s = idz.steps.empty() ? Eigen::VectorXd::LinSpaced(200, 0.0, 10.0 * theory.delay_s)
                                  : idz.steps.front().time_s;
  step.response = step.time_s.unaryExpr([&](double t) {
    return t < theory.delay_s ? 0.0 : (t - theory.delay_s) / theory.area_m2 + theory.p21_s_per_m2;
  });
  idz.steps.push_back(step);

  core::IdzModel identified;
  identified.delay_s = idz.model.at("delay_s").get<double>();
  identified.area_m2 = idz.model.at("area_m2").get<double>();
  identified.p21_s_per_m2 = idz.model.at("p21_s_per_m2").get<double>();
  identified.p22_s_per_m2 = idz.model.at("p22_s_per_m2").get<double>();
  const double low = 0.01 / theory.delay_s;
  const double high = std::min(100.0 / theory.delay_s, std::numbers::pi / table.sample_time_s());
  const Eigen::VectorXd omega =
      (Eigen::VectorXd::LinSpaced(kBodePoints, std::log10(low), std::log10(high)).array() *
       std::log(10.0))
          .exp();
  idz.bode.push_back(Bode("idz identified", identified, omega));
  idz.bode.push_back(Bode(label, theory, omega));
}

}  // namespace canalid::cli
