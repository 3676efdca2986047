#pragma once
#include <string>

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid theory` takes from the command line.
struct TheoryOptions {
  std::string canal;  ///< canal description (TOML, docs/canalsim.md)
  std::string pool;   ///< one pool's name, or empty with `all`
  bool all = false;
  double flow_m3s = 0.0;        ///< 0: the pool's flow at the canal's steady state
  std::string bode;             ///< write the frequency responses as CSV when not empty
  double bode_min_rad_s = 0.0;  ///< 0: 0.01 / the smallest delay
  double bode_max_rad_s = 0.0;  ///< 0: 100 / the smallest delay
  int bode_points = 200;
  bool pretty = false;
};

/// Registers `theory` on the app; `exit_code` receives the result when it runs.
void AddTheoryCommand(CLI::App& app, TheoryOptions& options, int& exit_code);

}  // namespace canalid::cli
