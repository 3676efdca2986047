// The report page's model table and escaping, on hand-written model JSON and a small table (no
// identification, no gnuplot).
#include "daemon/canalid/report_html.h"

#include <gtest/gtest.h>

#include "tests/support/run_program.h"

namespace canalid::cli {
namespace {

TEST(ReportHtml, NumbersHaveSixSignificantDigits) {
  EXPECT_EQ(ReportNumber(88.84966040835818), "88.8497");
  EXPECT_EQ(ReportNumber(0.003443130131554869), "0.00344313");
  EXPECT_EQ(ReportNumber(34661.804955209765), "34661.8");
  EXPECT_EQ(ReportNumber(1009199.9999999994), "1.0092e+06");
  EXPECT_EQ(ReportNumber(-15.0), "-15");
}

TEST(ReportHtml, RowHasMetricsDelayAreaAndTheOtherParameters) {
  const nlohmann::json id = nlohmann::json::parse(R"({
    "model": "id", "area_m2": 34661.8, "delay_s": 720.0, "nk": 12, "closed_loop": false,
    "metrics": {"fit_percent": 88.85, "rmse": 0.0034, "mae": 0.0026, "norm_error": 0.0228,
                "ise": 0.4},
    "inputs": ["q_in", "q_out"], "output": "level", "warnings": [],
    "input": {"file": "x.csv", "rows": 841, "sample_time_s": 60.0},
    "cross_check": {"iv_area_m2": 32037.1}})");
  const ModelRow row = ModelTableRow(id);
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"fit_percent", "88.85"}, {"rmse", "0.0034"}, {"mae", "0.0026"},
      {"norm_error", "0.0228"}, {"delay_s", "720"}, {"area_m2", "34661.8"}};
  EXPECT_EQ(row.metrics, expected);
  // Parameters in key order; bookkeeping (input, inputs, output, warnings, cross_check) and the
  // columns of their own (metrics, delay, area) left out.
  EXPECT_EQ(row.parameters, "closed_loop = false<br>nk = 12");
}

TEST(ReportHtml, MissingValuesAreEmptyCellsAndStructuresAreFlattened) {
  const nlohmann::json lpv = nlohmann::json::parse(R"({
    "model": "lpv", "coefficients": {"a1": [0.05, -0.2], "b<1>": [1, 2]}, "degree": 1})");
  const ModelRow row = ModelTableRow(lpv);
  for (const auto& [cls, text] : row.metrics) EXPECT_EQ(text, "") << cls;
  EXPECT_EQ(row.parameters, "coefficients = a1 = [0.05, -0.2]; b&lt;1&gt; = [1, 2]<br>degree = 1");
}

TEST(ReportHtml, PageEscapesNamesAndLinksEveryPlot) {
  const auto dir = testing::TestDirectory("ReportHtml.Page");
  const drivers::CsvTable table =
      drivers::CsvTable::Parse("time_s,q<in>,level\n0,1,2\n60,1.5,2.1\n", "a&b.csv");
  ModelAnalysis m;
  m.kind = "id";
  m.model = {{"model", "id"}, {"metrics", {{"fit_percent", 50.0}}}};
  m.notes = {"closed-loop <model>"};
  const std::vector<Plot> plots = {{"inputs.png", "gnuplot/inputs.gp", "record", "", "Inputs"},
                                   {"fit_id.png", "gnuplot/fit_id.gp", "fit", "id", "Fit"}};
  WriteReportHtml(dir / "index.html", table, "canalid report", {m}, plots);
  const std::string html = testing::ReadFile(dir / "index.html");
  EXPECT_NE(html.find("<code>a&amp;b.csv</code>: 2 samples every 60 s"), std::string::npos);
  EXPECT_NE(html.find("<code>q&lt;in&gt;</code>"), std::string::npos);
  EXPECT_NE(html.find("<img src=\"inputs.png\""), std::string::npos);
  EXPECT_NE(html.find("<img src=\"fit_id.png\""), std::string::npos);
  EXPECT_NE(html.find("Note: closed-loop &lt;model&gt;"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num fit_percent\">50</td>"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

}  // namespace
}  // namespace canalid::cli
