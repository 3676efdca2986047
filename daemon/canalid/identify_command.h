#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace CLI {
class App;
}

namespace canalid::drivers {
class CsvTable;
}

namespace canalid::cli {

/// Everything `canalid identify` takes from the command line.
struct IdentifyOptions {
  std::string model;
  std::string input;
  std::string out;  ///< also write the JSON here when not empty
  bool pretty = false;
  // id
  std::string qin = "q_in";
  std::string qout = "q_out";
  std::string level = "level";
  double max_delay_s = -1.0;
  std::string closed_loop = "auto";
  bool keep_outliers = false;
  // arx, foptd, soptd
  std::string u = "u";
  std::string y = "y";
  int na = 2;
  std::string nb = "2";
  std::string nk = "1";
  bool detrend = false;
};

/// Registers `identify` on the app; `exit_code` receives the result when it runs.
void AddIdentifyCommand(CLI::App& app, IdentifyOptions& options, int& exit_code);

/// One model kind each; they return the model JSON (DESIGN.md keys).  @throws InputError.
nlohmann::json IdentifyId(const IdentifyOptions& options, const drivers::CsvTable& table);
nlohmann::json IdentifyArx(const IdentifyOptions& options, const drivers::CsvTable& table);
nlohmann::json IdentifyProcessModel(const IdentifyOptions& options, const drivers::CsvTable& table);

}  // namespace canalid::cli
