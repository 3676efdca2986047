#pragma once
// A canalsim pool record of tests/data/sim (time_s,q_in,q_out,level) read for the core suites,
// without canalid's CSV reader (core tests do not link drivers/).
#include <Eigen/Core>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace canalid::core::testdata {

struct PoolRecord {
  double ts = 0.0;
  Eigen::VectorXd q_in, q_out, level;
};

inline PoolRecord ReadPoolRecord(const std::string& name) {
  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/" + name);
  std::string line;
  std::getline(in, line);  // header
  std::vector<double> t, qi, qo, y;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    double v[4];
    char comma;
    row >> v[0] >> comma >> v[1] >> comma >> v[2] >> comma >> v[3];
    t.push_back(v[0]);
    qi.push_back(v[1]);
    qo.push_back(v[2]);
    y.push_back(v[3]);
  }
  PoolRecord r;
  r.ts = t.at(1) - t.at(0);
  r.q_in = Eigen::Map<Eigen::VectorXd>(qi.data(), static_cast<Eigen::Index>(qi.size()));
  r.q_out = Eigen::Map<Eigen::VectorXd>(qo.data(), static_cast<Eigen::Index>(qo.size()));
  r.level = Eigen::Map<Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
  return r;
}

}  // namespace canalid::core::testdata
