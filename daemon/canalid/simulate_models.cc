#include <cmath>
#include <stdexcept>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_simulator.h"
#include "core/fractional/lpv_model.h"
#include "core/integrator_delay/idz_fit.h"
#include "core/integrator_delay/integrator_delay_model.h"
#include "core/linear/arx.h"
#include "core/linear/process_models.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/simulate_command.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/csv/csv_table.h"
#include "drivers/json/model_json_read.h"

namespace canalid::cli {
namespace {

// The input columns: --u, else the model's "inputs", else the kind's defaults.
std::vector<std::string> InputNames(const nlohmann::json& model, const std::string& source,
                                    const SimulateOptions& options,
                                    const std::vector<std::string>& defaults) {
  std::vector<std::string> names =
      options.u.empty() ? drivers::ModelInputs(model, source) : SplitList(options.u, "--u");
  if (names.empty()) names = defaults;
  if (!defaults.empty() && names.size() != defaults.size()) {
    throw InputError("--u: this model takes " + std::to_string(defaults.size()) +
                     " input column(s), got " + std::to_string(names.size()));
  }
  return names;
}

// Discrete models (nk, ARX coefficients) only mean something at the sampling they were fitted.
void RequireSampleTime(const drivers::CsvTable& table, double model_ts, const std::string& source) {
  const double ts = table.sample_time_s();
  if (std::abs(ts - model_ts) > 1e-9 * model_ts) {
    throw InputError(table.source() + ": sampled every " + std::to_string(ts) + " s but " + source +
                     " is a discrete model for sample_time_s = " + std::to_string(model_ts) + " s");
  }
}

// A pool model's simulation starts at row k0 (fit_from_sample) and needs two rows from there.
void RequireRowsFrom(const drivers::CsvTable& table, int k0) {
  if (table.rows() < k0 + 2) {
    throw InputError(table.source() + ": " + std::to_string(table.rows()) +
                     " rows; the model starts at row " + std::to_string(k0) +
                     " (fit_from_sample), needs at least 2 more");
  }
}

SimulatedOutput SimulateId(const nlohmann::json& model, const std::string& source,
                           const drivers::CsvTable& table, const SimulateOptions& options) {
  drivers::IntegratorDelayModelRecord r = drivers::IntegratorDelayModelFromJson(model, source);
  // A model written without its sample time is taken at the record's.
  if (r.model.sample_time_s > 0.0) {
    RequireSampleTime(table, r.model.sample_time_s, source);
  } else {
    r.model.sample_time_s = table.sample_time_s();
  }
  const auto names = InputNames(model, source, options, {"q_in", "q_out"});
  const auto q_in = RequireColumn(table, names[0]);
  const auto q_out = RequireColumn(table, names[1]);
  const int k0 = r.fit_from_sample;
  RequireRowsFrom(table, k0);
  Eigen::Vector4d theta(r.model.b, r.p21_s_per_m2, r.offset_m,
                        r.drift_m_per_s * r.model.sample_time_s);
  SimulatedOutput out;
  out.first_row = k0;
  out.y = core::OpenLoopRegressors(q_in, q_out, r.model.nk, k0) * theta;
  if (r.closed_loop) {
    out.warnings.push_back(
        "closed-loop model: simulated with the open-loop level equation and the measured q_out "
        "(the fit's own metrics used the three-step flow model)");
  }
  return out;
}

SimulatedOutput SimulateIdz(const nlohmann::json& model, const std::string& source,
                            const drivers::CsvTable& table, const SimulateOptions& options) {
  drivers::IdzModelRecord r = drivers::IdzModelFromJson(model, source);
  const double ts = r.sample_time_s > 0.0 ? r.sample_time_s : table.sample_time_s();
  if (r.sample_time_s > 0.0) RequireSampleTime(table, r.sample_time_s, source);
  r.model.drift_m_per_sample = r.drift_m_per_s * ts;
  const auto names = InputNames(model, source, options, {"q_in", "q_out"});
  const auto q_in = RequireColumn(table, names[0]);
  const auto q_out = RequireColumn(table, names[1]);
  const int k0 = r.fit_from_sample;
  RequireRowsFrom(table, k0);
  SimulatedOutput out;
  out.first_row = k0;
  out.y = core::IdzLevel(q_in, q_out, r.model, k0);
  return out;
}

SimulatedOutput SimulateArxModel(const nlohmann::json& model, const std::string& source,
                                 const drivers::CsvTable& table, const SimulateOptions& options) {
  const core::ArxModel arx = drivers::ArxModelFromJson(model, source);
  if (model.contains("sample_time_s") && model.at("sample_time_s").is_number()) {
    RequireSampleTime(table, model.at("sample_time_s").get<double>(), source);
  }
  const auto names = InputNames(model, source, options, {});
  if (names.size() != arx.orders.nb.size()) {
    throw InputError(source + ": the model has " + std::to_string(arx.orders.nb.size()) +
                     " inputs but " + std::to_string(names.size()) + " columns were named");
  }
  Eigen::MatrixXd u(table.rows(), static_cast<Eigen::Index>(names.size()));
  for (std::size_t i = 0; i < names.size(); ++i) {
    u.col(static_cast<Eigen::Index>(i)) = RequireColumn(table, names[i]);
  }
  // As identify does: the first outputs are the measured ones (initial conditions).
  const Eigen::Index warmup = std::max<Eigen::Index>(arx.first_sample, 1);
  if (table.rows() <= warmup) {
    throw InputError(table.source() + ": needs more than " + std::to_string(warmup) + " rows");
  }
  std::string output = options.y;
  if (output.empty() && model.contains("output") && model.at("output").is_string()) {
    output = model.at("output").get<std::string>();
  }
  // A model of deviations from a rest point (the daemon's batch arx): input_offset and
  // output_offset, one input; absent, 0 (the CLI's arx of the raw columns).
  const double input_offset = model.value("input_offset", 0.0);
  const double output_offset = model.value("output_offset", 0.0);
  if ((input_offset != 0.0 || output_offset != 0.0) && u.cols() != 1) {
    throw InputError(source + ": input_offset/output_offset need a one-input model");
  }
  u.array() -= input_offset;
  // The first outputs are the measured ones when the record has them, else the rest point.
  Eigen::VectorXd initial = Eigen::VectorXd::Zero(warmup);
  if (!output.empty() && table.HasColumn(output)) {
    initial = table.Column(output).head(warmup).array() - output_offset;
  }
  SimulatedOutput out;
  out.first_row = warmup;
  out.y = core::SimulateArx(arx, u, initial).tail(table.rows() - warmup).array() + output_offset;
  return out;
}

// The record starts with the plant at steady state at its first input value u[0]:
//   y = output_offset + K (u[0] - input_offset) + G(s) (u - u[0]),
// which is the identification's own convention when u[0] = input_offset (a round trip).
struct Deviations {
  Eigen::VectorXd du;
  double start_offset = 0.0;  // u[0] - input_offset
};
Deviations FromFirstInput(const drivers::CsvTable& table, const std::string& column,
                          double input_offset) {
  const auto u = RequireColumn(table, column);
  return {u.array() - u(0), u(0) - input_offset};
}

SimulatedOutput SimulateContinuous(const std::string& kind, const nlohmann::json& model,
                                   const std::string& source, const drivers::CsvTable& table,
                                   const SimulateOptions& options) {
  const std::string u = InputNames(model, source, options, {"u"})[0];
  const double ts = table.sample_time_s();
  SimulatedOutput out;
  if (kind == "foptd") {
    const auto r = drivers::FoptdFromJson(model, source);
    const Deviations d = FromFirstInput(table, u, r.input_offset);
    out.y = core::Simulate(r.model, d.du, ts).array() +
            (r.output_offset + r.model.gain * d.start_offset);
  } else if (kind == "soptd") {
    const auto r = drivers::SoptdFromJson(model, source);
    const Deviations d = FromFirstInput(table, u, r.input_offset);
    out.y = core::Simulate(r.model, d.du, ts).array() +
            (r.output_offset + r.model.gain * d.start_offset);
  } else {
    const drivers::FractionalFoptdRecord r = drivers::FractionalFoptdFromJson(model, source);
    const Deviations d = FromFirstInput(table, u, r.params.input_offset);
    const double level = r.params.output_offset + r.params.model.gain * d.start_offset;
    // Without a recorded band: the one the fit would have used on this record.
    core::OustaloupFoptdSimulator sim(r.params.model, ts, r.Band(ts, d.du.size()));
    out.y.resize(d.du.size());
    for (Eigen::Index k = 0; k < d.du.size(); ++k) {
      out.y(k) = sim.output() + level;
      sim.Advance(d.du(k));
    }
  }
  return out;
}

SimulatedOutput SimulateFracSs(const nlohmann::json& model, const std::string& source,
                               const drivers::CsvTable& table, const SimulateOptions& options) {
  const drivers::CommensurateRecord r = drivers::CommensurateFromJson(model, source);
  if (r.sample_time_s > 0.0) RequireSampleTime(table, r.sample_time_s, source);
  const std::string u = InputNames(model, source, options, {"u"})[0];
  const Deviations d = FromFirstInput(table, u, r.model.input_offset);
  SimulatedOutput out;
  // The LPV paper's companion form has unit static gain.
  out.y = core::SimulateCommensurate(r.model.model, d.du, r.memory_length).array() +
          (r.model.output_offset + d.start_offset);
  return out;
}

SimulatedOutput SimulateLpv(const nlohmann::json& model, const std::string& source,
                            const drivers::CsvTable& table, const SimulateOptions& options) {
  const drivers::LpvRecord r = drivers::LpvFromJson(model, source);
  if (r.model.kind != "first_order_arx") {
    throw InputError(source + ": key 'local_model': '" + r.local_model +
                     "': simulation along a scheduling trajectory exists for arx locals only");
  }
  if (model.contains("sample_time_s") && model.at("sample_time_s").is_number()) {
    RequireSampleTime(table, model.at("sample_time_s").get<double>(), source);
  }
  const std::string u = InputNames(model, source, options, {"u"})[0];
  const Eigen::VectorXd theta =
      RequireColumn(table, options.schedule.empty() ? r.schedule : options.schedule);
  const Eigen::VectorXd du = RequireColumn(table, u).array() - r.input_offset;
  SimulatedOutput out;
  out.y = core::SimulateLpvArx(r.model, du, theta).array() + r.output_offset;
  return out;
}

}  // namespace

SimulatedOutput SimulateModel(const nlohmann::json& model, const std::string& source,
                              const drivers::CsvTable& table, const SimulateOptions& options) {
  try {
    const std::string kind = drivers::ModelKind(model, source);
    SimulatedOutput out;
    if (kind == "id") {
      out = SimulateId(model, source, table, options);
    } else if (kind == "idz") {
      out = SimulateIdz(model, source, table, options);
    } else if (kind == "arx") {
      out = SimulateArxModel(model, source, table, options);
    } else if (kind == "foptd" || kind == "soptd" || kind == "frac-foptd") {
      out = SimulateContinuous(kind, model, source, table, options);
    } else if (kind == "frac-ss") {
      out = SimulateFracSs(model, source, table, options);
    } else if (kind == "lpv") {
      out = SimulateLpv(model, source, table, options);
    } else {
      throw InputError(source + ": key 'model': unknown kind '" + kind +
                       "' (id, idz, arx, foptd, soptd, frac-foptd, frac-ss, lpv)");
    }
    RequireFiniteOutput(out.y, out.first_row, table, source + " (model '" + kind + "')");
    return out;
  } catch (const drivers::ModelJsonError& e) {
    throw InputError(e.what());
  } catch (const std::invalid_argument& e) {
    throw InputError(source + ": " + e.what());
  }
}

}  // namespace canalid::cli
