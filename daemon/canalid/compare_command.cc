#include <glob.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/linear/process_model_fit.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {
namespace {

const std::vector<std::string> kComparable = {"foptd", "soptd", "frac-foptd", "frac-ss"};

std::vector<std::string> ExpandGlob(const std::string& pattern) {
  glob_t found{};
  // glob(3) is not thread-safe (it reads the environment and locale); canalid runs on one thread.
  // NOLINTNEXTLINE(concurrency-mt-unsafe)
  const int status = glob(pattern.c_str(), 0, nullptr, &found);
  std::vector<std::string> files;
  if (status == 0) {
    for (std::size_t i = 0; i < found.gl_pathc; ++i) files.emplace_back(found.gl_pathv[i]);
  }
  globfree(&found);
  if (status == GLOB_NOMATCH || files.empty()) {
    throw InputError("--input: no file matches '" + pattern + "'");
  }
  if (status != 0) throw InputError("--input: cannot expand '" + pattern + "'");
  return files;  // glob(3) sorts them
}

double NormError(const std::string& kind, const IdentifyOptions& options,
                 const Eigen::Ref<const Eigen::VectorXd>& u,
                 const Eigen::Ref<const Eigen::VectorXd>& y, double ts) {
  if (kind == "foptd") return core::FitFoptd(u, y, ts).metrics.norm_error;
  if (kind == "soptd") return core::FitSoptd(u, y, ts).metrics.norm_error;
  if (kind == "frac-foptd") return core::FitFractionalFoptd(u, y, ts).metrics.norm_error;
  const int max_delay = static_cast<int>(std::min<Eigen::Index>(u.size() / 10, 100));
  return core::FitCommensurateScanDelay(u, y, options.q > 0 ? options.q : 2, max_delay, ts)
      .metrics.norm_error;
}

struct Summary {
  double mean = 0.0;
  double max = 0.0;
  double std = 0.0;  // sample standard deviation (n - 1), 0 for one file
};

Summary Summarise(const std::vector<double>& v) {
  Summary s;
  for (double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  s.max = *std::max_element(v.begin(), v.end());
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  return s;
}

}  // namespace

int RunCompare(const IdentifyOptions& options) {
  const std::vector<std::string> kinds = SplitList(options.compare, "--compare");
  for (const std::string& kind : kinds) {
    if (std::find(kComparable.begin(), kComparable.end(), kind) == kComparable.end()) {
      throw InputError("--compare: '" + kind + "' is not a kind it compares (foptd, soptd, " +
                       "frac-foptd, frac-ss)");
    }
  }
  const std::vector<std::string> files = ExpandGlob(options.input);
  const bool progress = isatty(STDERR_FILENO) == 1;
  std::vector<std::vector<double>> errors(kinds.size());
  nlohmann::json per_file = nlohmann::json::array();
  for (std::size_t f = 0; f < files.size(); ++f) {
    if (progress) std::cerr << "\rfile " << f + 1 << "/" << files.size() << ": " << files[f];
    const drivers::CsvTable table = ReadTable(files[f]);
    const auto u = RequireMovingColumn(table, options.u);
    const auto y = RequireColumn(table, options.y);
    nlohmann::json entry = {{"file", files[f]}, {"rows", table.rows()}};
    for (std::size_t k = 0; k < kinds.size(); ++k) {
      try {
        const double e = NormError(kinds[k], options, u, y, table.sample_time_s());
        errors[k].push_back(e);
        entry["norm_error"][kinds[k]] = e;
      } catch (const std::invalid_argument& e) {
        throw InputError(files[f] + ": " + kinds[k] + ": " + e.what());
      }
    }
    per_file.push_back(entry);
  }
  if (progress) std::cerr << "\n";

  nlohmann::json summary = nlohmann::json::object();
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    const Summary s = Summarise(errors[k]);
    summary[kinds[k]] = {{"mean", s.mean}, {"max", s.max}, {"std", s.std}};
  }
  if (options.json) {
    const nlohmann::json out = {
        {"files", files.size()}, {"norm_error", summary}, {"per_file", per_file}};
    std::cout << (options.pretty ? out.dump(2) : out.dump()) << std::endl;
    return 0;
  }
  std::printf("norm_error = sqrt(ISE/t_f)/|dy| over %zu files (the flume paper, Table 1)\n",
              files.size());
  std::printf("%-12s %12s %12s %12s\n", "model", "mean", "max", "std");
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    const Summary s = Summarise(errors[k]);
    std::printf("%-12s %12.6f %12.6f %12.6f\n", kinds[k].c_str(), s.mean, s.max, s.std);
  }
  std::fflush(stdout);
  return 0;
}

}  // namespace canalid::cli
