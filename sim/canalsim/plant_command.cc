#include "sim/canalsim/plant_command.h"

#include <algorithm>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "drivers/csv/csv_table.h"
#include "drivers/json/model_json_read.h"
#include "sim/canalsim/model_plant_json.h"

namespace canalid::sim {
namespace {

constexpr int kExitCantCreat = 73;  // EX_CANTCREAT
constexpr int kExitConfig = 78;     // EX_CONFIG

std::vector<std::string> SplitComma(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) items.push_back(item);
  return items;
}

// The input columns: --u, else the model's "inputs" (lpv: and its schedule), else the kind's
// defaults (id: q_in, q_out; others: u).
std::vector<std::string> InputColumns(const nlohmann::json& model, const std::string& source,
                                      const std::string& u_option) {
  if (!u_option.empty()) return SplitComma(u_option);
  const std::string kind = drivers::ModelKind(model, source);
  std::vector<std::string> names = drivers::ModelInputs(model, source);
  if (names.empty()) {
    names = kind == "id" || kind == "idz" ? std::vector<std::string>{"q_in", "q_out"}
                                          : std::vector<std::string>{"u"};
  }
  if (kind == "lpv") {
    names.resize(1);
    names.push_back(drivers::LpvFromJson(model, source).schedule);
  }
  return names;
}

}  // namespace

PlantCommand::PlantCommand(CLI::App& app) {
  command_ = app.add_subcommand(
      "plant", std::string("Drive the plant of a canalid model JSON (") + kModelPlantKinds +
                   ") with the inputs of a CSV, row by row, and write its output as CSV; the same "
                   "output as `canalid simulate` (docs/canalsim.md)");
  command_->add_option("--model-json", model_path_, "Model JSON written by canalid identify")
      ->required()
      ->check(CLI::ExistingFile);
  command_->add_option("--input", input_path_, "CSV with time_s and the input columns")
      ->required()
      ->check(CLI::ExistingFile);
  command_->add_option("--out", out_path_, "Output CSV: time_s and the plant output")->required();
  command_->add_option(
      "--u", u_,
      "Input columns, comma-separated (default: the model's inputs; id q_in,q_out; "
      "lpv the input then the scheduling column; others u)");
  command_->add_option("--column", column_, "Name of the output column")->capture_default_str();
}

int PlantCommand::Run() const {
  try {
    std::ifstream file(model_path_);
    const nlohmann::json model = nlohmann::json::parse(file);
    const drivers::CsvTable table = drivers::CsvTable::Read(input_path_);
    const std::vector<std::string> names = InputColumns(model, model_path_, u_);
    Eigen::MatrixXd u(table.rows(), static_cast<Eigen::Index>(names.size()));
    for (std::size_t i = 0; i < names.size(); ++i) {
      u.col(static_cast<Eigen::Index>(i)) = table.Column(names[i]);
    }
    // arx starts from the measured outputs when the CSV has them, as canalid simulate does.
    Eigen::VectorXd initial_outputs;
    if (drivers::ModelKind(model, model_path_) == "arx" && model.contains("output") &&
        model.at("output").is_string() && table.HasColumn(model.at("output"))) {
      const Eigen::Index warmup =
          std::max<Eigen::Index>(drivers::ArxModelFromJson(model, model_path_).first_sample, 1);
      initial_outputs = table.Column(model.at("output")).head(std::min(warmup, table.rows()));
    }
    auto plant = PlantFromModelJson(model, model_path_, table.sample_time_s(), u.row(0).transpose(),
                                    initial_outputs);
    if (plant->input_count() != u.cols()) {
      throw std::invalid_argument(model_path_ + ": the plant takes " +
                                  std::to_string(plant->input_count()) + " inputs, --u names " +
                                  std::to_string(u.cols()));
    }
    Eigen::VectorXd y(table.rows());
    for (Eigen::Index k = 0; k < table.rows(); ++k) {
      const Eigen::VectorXd uk = u.row(k).transpose();
      y(k) = plant->Output(uk);
      plant->Advance(uk);
    }
    try {
      drivers::WriteCsv(out_path_, {"time_s", column_}, {table.time_s(), y});
    } catch (const drivers::CsvError& e) {
      std::cerr << "canalsim: " << e.what() << '\n';
      return kExitCantCreat;
    }
  } catch (const nlohmann::json::exception& e) {
    std::cerr << "canalsim: " << model_path_ << ": " << e.what() << '\n';
    return kExitConfig;
  } catch (const std::exception& e) {
    // Model JSON, CSV and plant errors all name the file and key or column.
    std::cerr << "canalsim: " << e.what() << '\n';
    return kExitConfig;
  }
  return 0;
}

}  // namespace canalid::sim
