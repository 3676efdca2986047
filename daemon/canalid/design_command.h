#pragma once
#include <cstdint>
#include <string>

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid design` takes from the command line.
struct DesignOptions {
  double nominal_flow_m3s = 0.0;
  double delay_s = 0.0;
  double sample_time_s = 0.0;
  double amplitude_percent = 7.5;
  std::string csv;  ///< write the PRBS as time_s,value when not empty
  std::uint32_t seed = 1;
  bool pretty = false;
};

/// Registers `design` on the app; `exit_code` receives the result when it runs.
void AddDesignCommand(CLI::App& app, DesignOptions& options, int& exit_code);

}  // namespace canalid::cli
