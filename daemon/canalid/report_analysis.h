#pragma once
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// One step response: the model's output change after a unit step of its first input at t = 0.
struct StepCurve {
  std::string label;
  Eigen::VectorXd time_s;  ///< since the step
  Eigen::VectorXd response;
};

/// One frequency response: gain and phase of the model's level response to its inflow.
struct BodeCurve {
  std::string label;
  Eigen::VectorXd omega_rad_s;
  Eigen::VectorXd gain;  ///< output units per input unit
  Eigen::VectorXd phase_deg;
};

/// An LPV model's parameters against the scheduling variable: the polynomials on a grid and the
/// local estimates at the operating points' mean theta.
struct LpvCurves {
  std::string schedule;
  std::vector<std::string> parameters;
  std::vector<double> band_edges;
  Eigen::VectorXd theta_grid;
  Eigen::MatrixXd polynomial;  ///< one row per grid point, one column per parameter
  Eigen::VectorXd theta_points;
  Eigen::MatrixXd local;  ///< one row per operating point, one column per parameter
};

/// What the report shows of one identified model.
struct ModelAnalysis {
  std::string kind;
  nlohmann::json model;  ///< as `canalid identify` prints it
  /// Simulation over the record (canalid simulate's SimulateModel); empty when the kind has none.
  std::string output;
  Eigen::VectorXd time_s;
  Eigen::VectorXd measured;
  Eigen::VectorXd simulated;
  Eigen::VectorXd residual;  ///< measured - simulated
  /// Normalised residual autocorrelation r(0..max_lag) and the 99 % band +-z/sqrt(N) of white
  /// noise (core::CrossCorrelation, core::TwoSidedNormalQuantile).
  Eigen::VectorXd autocorrelation;
  double band_99 = 0.0;
  std::vector<StepCurve> steps;
  /// Frequency responses compared in one figure (idz beside the geometry's model); may be empty.
  std::vector<BodeCurve> bode;
  bool has_lpv = false;
  LpvCurves lpv;
  std::vector<std::string> notes;  ///< what could not be shown, and why; simulation warnings
};

/// Lags of the residual autocorrelation (MATLAB resid's default).
inline constexpr int kResidualLags = 25;

/// Simulates `model` (of `kind`, identified on `table`) on the record, forms residuals and their
/// autocorrelation, its unit-step responses (every LPV operating point for lpv) and, for lpv,
/// the parameter curves.  A kind without a simulation (lpv with non-arx locals) gets a note.
/// @throws InputError on a model that does not fit the table.
ModelAnalysis AnalyseModel(const std::string& kind, const nlohmann::json& model,
                           const drivers::CsvTable& table);

}  // namespace canalid::cli
