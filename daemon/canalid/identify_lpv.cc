#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/lpv_model.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

// Delay range of the discrete local kinds when --max-delay-s is not given.
constexpr int kDefaultLocalMaxDelaySamples = 20;

std::string Text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

[[noreturn]] void ThrowEmptyEdge(const std::string& option, const std::string& text) {
  throw InputError(option + ": empty item in '" + text + "'");
}

[[noreturn]] void ThrowNotANumber(const std::string& option, const std::string& item) {
  throw InputError(option + ": '" + item + "' is not a number");
}

std::vector<double> ParseEdges(std::string text, const std::string& option) {
  // "1,,2" or a trailing comma is a typo, not two edges.
  bool item_since_comma = false;
  for (char c : text) {
    if (c == ',') {
      if (!item_since_comma) ThrowEmptyEdge(option, text);
      item_since_comma = false;
    } else if (!std::isspace(static_cast<unsigned char>(c))) {
      item_since_comma = true;
    }
  }
  if (!item_since_comma && text.find(',') != std::string::npos) ThrowEmptyEdge(option, text);
  for (char& c : text) {
    if (c == ',' || c == ';' || c == '\n' || c == '\t' || c == '\r') c = ' ';
  }
  std::istringstream in(text);
  std::vector<double> edges;
  std::string item;
  while (in >> item) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end != item.c_str() + item.size() || !std::isfinite(v)) {
      ThrowNotANumber(option, item);
    }
    edges.push_back(v);
  }
  if (edges.size() < 2) {
    throw InputError(option + ": needs at least two band edges b0,b1 (got " +
                     std::to_string(edges.size()) + ")");
  }
  for (std::size_t i = 1; i < edges.size(); ++i) {
    if (!(edges[i] > edges[i - 1])) {
      throw InputError(option + ": band edges must increase strictly, but " + Text(edges[i]) +
                       " follows " + Text(edges[i - 1]));
    }
  }
  return edges;
}

std::vector<double> Edges(const IdentifyOptions& options) {
  if (options.bands.empty() == options.bands_file.empty()) {
    throw InputError("--model lpv needs the band edges: either --bands b0,b1,... or --bands-file");
  }
  if (!options.bands.empty()) return ParseEdges(options.bands, "--bands");
  std::ifstream in(options.bands_file);
  if (!in) throw InputError(options.bands_file + ": cannot open file (--bands-file)");
  std::stringstream text;
  text << in.rdbuf();
  return ParseEdges(text.str(), options.bands_file);
}

core::LocalModelKind LocalKind(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const int max_delay =
      options.max_delay_s > 0.0
          ? std::max(1, OptionSamples(options.max_delay_s, table, "--max-delay-s", true))
          : kDefaultLocalMaxDelaySamples;
  if (options.local == "arx") return core::FirstOrderArxKind(max_delay);
  if (options.local == "frac-foptd") return core::FractionalFoptdKind();
  if (options.local == "frac-ss")
    return core::CommensurateKind(options.q > 0 ? options.q : 2, max_delay);
  if (options.local == "integer") return core::IntegratorWaveKind();
  throw InputError("--local: unknown local model kind '" + options.local +
                   "' (arx, frac-foptd, frac-ss, integer)");
}

}  // namespace

nlohmann::json IdentifyLpv(const IdentifyOptions& options, const drivers::CsvTable& table) {
  if (options.local.empty()) throw InputError("--model lpv needs --local KIND");
  if (options.schedule.empty()) throw InputError("--model lpv needs --schedule COLUMN");
  const double ts = table.sample_time_s();
  const core::LocalModelKind kind = LocalKind(options, table);
  const std::vector<double> edges = Edges(options);
  const auto u = RequireMovingColumn(table, options.u);
  const auto y = RequireColumn(table, options.y);
  const auto theta = RequireColumn(table, options.schedule);
  // Every band must hold an operating point: a short one would give a local model fitted on
  // too little data and silently bend the polynomials.
  for (const core::LpvOperatingPoint& p : core::SplitByScheduling(theta, edges)) {
    if (p.length < options.min_band_samples) {
      throw InputError(table.source() + ": band [" + Text(p.theta_low) + ", " + Text(p.theta_high) +
                       ") of '" + options.schedule + "' has " + std::to_string(p.length) +
                       " consecutive samples, needs at least " +
                       std::to_string(options.min_band_samples) + " (--min-band-samples)");
    }
  }
  if (static_cast<int>(edges.size()) - 1 < options.degree + 1) {
    throw InputError("--bands: " + std::to_string(edges.size() - 1) + " bands, degree " +
                     std::to_string(options.degree) + " needs at least " +
                     std::to_string(options.degree + 1) + " (--degree)");
  }
  try {
    const core::LpvIdentification lpv =
        core::IdentifyLpv(u, y, theta, ts, edges, kind, options.degree, options.min_band_samples);
    nlohmann::json json = drivers::ToJson(lpv, ts);
    json["local_model"] = options.local;
    json["schedule"] = options.schedule;
    json["bands"] = edges;
    json["inputs"] = std::vector<std::string>{options.u};
    json["output"] = options.y;
    json["sample_time_s"] = ts;
    json["input_offset"] = u(0);
    json["output_offset"] = y(0);
    // The whole record along its theta trajectory (core has that simulation for arx locals).
    if (options.local == "arx") {
      const Eigen::VectorXd du = u.array() - u(0);
      const Eigen::VectorXd simulated = core::SimulateLpvArx(lpv.model, du, theta).array() + y(0);
      json["metrics"] = drivers::ToJson(core::ComputeMetrics(y, simulated, ts));
    }
    return json;
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
}

}  // namespace canalid::cli
