#include "daemon/canalid/report_html.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "daemon/canalid/child_process.h"

namespace canalid::cli {
namespace {

// Keys shown in their own columns or not parameters of the model at all.
const std::set<std::string> kNotParameters = {"model",
                                              "metrics",
                                              "input",
                                              "inputs",
                                              "output",
                                              "warnings",
                                              "preprocessing",
                                              "cross_check",
                                              "metrics_per_band",
                                              "initial",
                                              "oustaloup",
                                              "simulations",
                                              "equations",
                                              "delay_s",
                                              "area_m2",
                                              "closed_loop_reason",
                                              "bands",
                                              "local_model",
                                              "schedule",
                                              "kind",
                                              "converged",
                                              "parameter_std",
                                              "fpe",
                                              "aic",
                                              "loss"};

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string ValueText(const nlohmann::json& v) {
  if (v.is_number()) return ReportNumber(v.get<double>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string text = "[";
    for (std::size_t i = 0; i < v.size(); ++i) text += (i ? ", " : "") + ValueText(v[i]);
    return text + "]";
  }
  if (v.is_object()) {
    std::string text;
    for (const auto& [key, item] : v.items()) {
      text += (text.empty() ? "" : "; ") + key + " = " + ValueText(item);
    }
    return text;
  }
  return "";
}

std::string Metric(const nlohmann::json& model, const std::string& key) {
  if (!model.contains("metrics") || !model.at("metrics").contains(key)) return "";
  return ReportNumber(model.at("metrics").at(key).get<double>());
}

}  // namespace

std::string ReportNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

ModelRow ModelTableRow(const nlohmann::json& model) {
  ModelRow row;
  for (const char* key : {"fit_percent", "rmse", "mae", "norm_error"}) {
    row.metrics.emplace_back(key, Metric(model, key));
  }
  for (const char* key : {"delay_s", "area_m2"}) {
    row.metrics.emplace_back(key, model.contains(key) && model.at(key).is_number()
                                      ? ReportNumber(model.at(key).get<double>())
                                      : "");
  }
  for (const auto& [key, value] : model.items()) {
    if (kNotParameters.count(key)) continue;
    row.parameters +=
        (row.parameters.empty() ? "" : "<br>") + Escape(key) + " = " + Escape(ValueText(value));
  }
  return row;
}

void WriteReportHtml(const std::filesystem::path& path, const drivers::CsvTable& table,
                     const std::string& command_line, const std::vector<ModelAnalysis>& models,
                     const std::vector<Plot>& plots) {
  std::ostringstream h;
  const Eigen::VectorXd t = table.time_s();
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<title>canalid report: " << Escape(table.source()) << "</title>\n<style>\n"
    << "body{font-family:sans-serif;max-width:1000px;margin:1em auto;padding:0 1em;color:#222}\n"
    << "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.3em "
       ".6em;vertical-align:top}\n"
    << "td.num{text-align:right;font-variant-numeric:tabular-nums}img{max-width:100%}\n"
    << "figure{margin:1.5em 0}figcaption{color:#555}pre{background:#f6f6f6;padding:.5em;"
       "overflow-x:auto}\n"
    << "</style>\n</head>\n<body>\n<h1>canalid report</h1>\n"
    << "<p>Record <code>" << Escape(table.source()) << "</code>: " << table.rows()
    << " samples every " << ReportNumber(table.sample_time_s()) << " s, from " << ReportNumber(t(0))
    << " s to " << ReportNumber(t(t.size() - 1)) << " s; columns ";
  for (std::size_t i = 0; i < table.columns().size(); ++i) {
    h << (i ? ", " : "") << "<code>" << Escape(table.columns()[i]) << "</code>";
  }
  h << ".</p>\n<p>Made by <code>" << Escape(command_line) << "</code>.</p>\n";

  h << "<h2 id=\"models\">Models and metrics</h2>\n"
    << "<p>Metrics as <code>canalid identify</code> prints them (simulation, not one-step "
       "prediction): fit % = 100 (1 - |y - &#375;| / |y - mean y|), RMSE and MAE in the output's "
       "unit, normalised error sqrt(ISE/t<sub>f</sub>)/|&Delta;y|.</p>\n"
    << "<table id=\"model-table\">\n<tr><th>model</th><th>fit %</th><th>RMSE</th><th>MAE</th>"
       "<th>norm. error</th><th>delay (s)</th><th>area (m&sup2;)</th><th>parameters</th></tr>\n";
  for (const auto& m : models) {
    const ModelRow row = ModelTableRow(m.model);
    h << "<tr id=\"model-" << Escape(m.kind) << "\"><th>" << Escape(m.kind) << "</th>";
    for (const auto& [cls, text] : row.metrics) {
      h << "<td class=\"num " << cls << "\">" << text << "</td>";
    }
    h << "<td class=\"parameters\">" << row.parameters << "</td></tr>\n";
  }
  h << "</table>\n";

  const std::vector<std::pair<std::string, std::string>> sections = {
      {"record", "Inputs and output"},
      {"fit", "Measured and simulated output"},
      {"residuals", "Residuals and their autocorrelation"},
      {"steps", "Step responses"},
      {"lpv", "LPV parameters against the scheduling variable"},
      {"online", "Online estimates over the log (+-2 sigma)"}};
  for (const auto& [section, heading] : sections) {
    bool opened = false;
    for (const auto& p : plots) {
      if (p.section != section) continue;
      if (!opened) h << "<h2 id=\"" << section << "\">" << heading << "</h2>\n";
      opened = true;
      h << "<figure><img src=\"" << Escape(p.image) << "\" alt=\"" << Escape(p.title)
        << "\"><figcaption>" << Escape(p.title) << " (<a href=\"" << Escape(p.script)
        << "\">gnuplot script</a>)";
      // The caveats of a model belong next to its picture, where they are read.
      for (const auto& m : models) {
        if (p.section != "fit" || m.kind != p.model) continue;
        for (const auto& n : m.notes) h << "<br>Note: " << Escape(n);
      }
      h << "</figcaption></figure>\n";
    }
  }

  h << "<h2 id=\"notes\">Notes and model JSON</h2>\n";
  for (const auto& m : models) {
    h << "<h3>" << Escape(m.kind) << "</h3>\n";
    if (!m.notes.empty()) {
      h << "<ul>\n";
      for (const auto& n : m.notes) h << "<li>" << Escape(n) << "</li>\n";
      h << "</ul>\n";
    }
    h << "<p><a href=\"models/" << Escape(m.kind) << ".json\">models/" << Escape(m.kind)
      << ".json</a> (for <code>canalid simulate --model-json</code>)</p>\n"
      << "<details><summary>JSON</summary><pre>" << Escape(m.model.dump(2)) << "</pre></details>\n";
  }
  h << "</body>\n</html>\n";
  std::ofstream out(path, std::ios::trunc);
  if (!(out << h.str()) || !out.flush()) throw ToolError(path.string() + ": cannot write");
}

}  // namespace canalid::cli
