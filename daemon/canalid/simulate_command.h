#pragma once
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace canalid::drivers {
class CsvTable;
}

namespace canalid::cli {

/// Everything `canalid simulate` takes from the command line.
struct SimulateOptions {
  std::string model_json;
  std::string input;
  std::string out;
  std::string u;         ///< overrides the model's input columns (comma-separated)
  std::string y;         ///< measured output column for metrics (default: the model's "output")
  std::string schedule;  ///< lpv: overrides the model's scheduling column
};

/// Registers `simulate` on the app; `exit_code` receives the result when it runs.
void AddSimulateCommand(CLI::App& app, SimulateOptions& options, int& exit_code);

/// The model's output for rows first_row..N-1 of the table (earlier rows only feed delays or
/// initial conditions: id from fit_from_sample, arx from max(fit_from_sample, 1)).
struct SimulatedOutput {
  Eigen::Index first_row = 0;
  Eigen::VectorXd y;
  std::vector<std::string> warnings;
};

/// Simulates any model JSON `canalid identify` writes on the table's input columns.
/// @throws InputError on a bad model (file and key named) or missing columns.
SimulatedOutput SimulateModel(const nlohmann::json& model, const std::string& source,
                              const drivers::CsvTable& table, const SimulateOptions& options);

}  // namespace canalid::cli
