#pragma once
#include <CLI/CLI.hpp>
#include <string>

namespace canalid::sim {

/// `canalsim plant`: a transfer-function plant built from a `canalid identify` model JSON
/// (sim/canalsim/model_plant_json.h) driven row by row with the inputs of a CSV, its output
/// written as CSV: the fast plant for unit tests and rigs that do not need Saint-Venant.
/// Registers the sub-command and its options on construction; Run() after a successful parse.
class PlantCommand final {
 public:
  explicit PlantCommand(CLI::App& app);
  bool selected() const { return command_->parsed(); }
  /// Returns the exit code: 0, 78 for a model or input problem (one line on stderr), 73 if the
  /// output cannot be written.
  int Run() const;

 private:
  CLI::App* command_;
  std::string model_path_;
  std::string input_path_;
  std::string out_path_;
  std::string u_;
  std::string column_ = "y";
};

}  // namespace canalid::sim
