#pragma once
// tests/data/reference/frac_step_reference.csv: exact unit-step responses K (1 - E_alpha(-t^alpha /
// T)) of K/(1 + T s^alpha) (sources in tests/data/reference/README.md), for the suites that hold
// the Mittag-Leffler function, the fractional simulators and `canalid simulate` against them.
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::testing {

struct FracStepReferenceRow {
  double gain, time_constant_s, alpha, t_s, response;
};

/// Every row of the table; throws naming the file and line when one is not five numbers.
inline std::vector<FracStepReferenceRow> ReadFracStepReference() {
  const std::string path = std::string(CANALID_REFERENCE_DIR) + "/frac_step_reference.csv";
  std::ifstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot open");
  std::vector<FracStepReferenceRow> rows;
  std::string line;
  std::getline(file, line);  // header
  for (int number = 2; std::getline(file, line); ++number) {
    std::stringstream ss(line);
    std::vector<double> v;
    for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
    if (v.size() != 5) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected 5 numbers");
    }
    rows.push_back({v[0], v[1], v[2], v[3], v[4]});
  }
  return rows;
}

}  // namespace canalid::testing
