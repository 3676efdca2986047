// `canalid report` run as a program on a canal PRBS record, a fractional gate-step record and an
// LPV record: every figure index.html links exists and is a real picture (PNG decoded here with
// libpng, independently of gnuplot and cairo), the table carries the numbers `canalid identify`
// prints, the step responses match closed forms, and bad input and a broken gnuplot are reported.
#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/csv/csv_table.h"
#include "tests/support/frac_gate_step.h"
#include "tests/support/lpv_record.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

const std::string kPrbs = std::string(CANALID_SOURCE_DIR) + "/tests/data/sim/asce2-pool2-prbs.csv";

// Figures are pngcairo 960x480 (report_plots.cc).  A failed or empty picture is a few hundred
// bytes; axes and text alone already make ~15 kB, so the size only rules out the former.
constexpr int kWidth = 960;
constexpr int kHeight = 480;
constexpr std::uintmax_t kMinPngBytes = 8000;

std::uint32_t BigEndian32(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
  return v;
}

// What a PNG holds: its IHDR size read from the bytes, and from the decoded RGB pixels the share
// drawn in colour (max - min channel > 64): the curves, since axes, grid and text are grey.
struct PngFacts {
  bool signature = false;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  double coloured_fraction = 0.0;
};

PngFacts InspectPng(const std::filesystem::path& path) {
  PngFacts facts;
  const std::string bytes = ReadFile(path);
  const std::string signature = "\x89PNG\r\n\x1a\n";
  facts.signature =
      bytes.size() > 33 && bytes.compare(0, 8, signature) == 0 && bytes.compare(12, 4, "IHDR") == 0;
  if (!facts.signature) return facts;
  facts.width = BigEndian32(bytes, 16);
  facts.height = BigEndian32(bytes, 20);
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return facts;
  image.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> pixels(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, pixels.data(), 0, nullptr)) return facts;
  std::size_t coloured = 0;
  for (std::size_t i = 0; i + 2 < pixels.size(); i += 3) {
    const int high = std::max({pixels[i], pixels[i + 1], pixels[i + 2]});
    const int low = std::min({pixels[i], pixels[i + 1], pixels[i + 2]});
    if (high - low > 64) ++coloured;
  }
  const std::size_t rgb_pixels = pixels.size() / 3;
  facts.coloured_fraction = static_cast<double>(coloured) / static_cast<double>(rgb_pixels);
  return facts;
}

// Every <img src="..."> of the page.
std::vector<std::string> ImageLinks(const std::string& html) {
  std::vector<std::string> links;
  const std::regex img("<img src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator();
       ++it) {
    links.push_back((*it)[1]);
  }
  return links;
}

// The text of the table cell of `metric` in the row of model `kind`.
std::string Cell(const std::string& html, const std::string& kind, const std::string& metric) {
  const std::regex row("<tr id=\"model-" + kind + "\">(.*?)</tr>");
  std::smatch m;
  if (!std::regex_search(html, m, row)) return "no row";
  const std::string cells = m[1];
  const std::regex cell("<td class=\"num " + metric + "\">([^<]*)</td>");
  std::smatch c;
  return std::regex_search(cells, c, cell) ? std::string(c[1]) : "no cell";
}

// printf's %.6g of the number identify printed: the table shows 6 significant digits.
std::string SixDigits(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}

// Columns of a whitespace-separated gnuplot data file (the '#' header line skipped).
std::vector<std::vector<double>> ReadData(const std::filesystem::path& path) {
  std::vector<std::vector<double>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::vector<double> row;
    std::string cell;
    while (s >> cell) row.push_back(cell == "NaN" ? NAN : std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// The flume paper's flume: a gate step at 6 s, Ts = 0.15 s, level from the exact Mittag-Leffler
// response of K e^{-tau s}/(1 + T s^alpha) plus seeded noise (as tests/cli/fractional_cli_test.cc).
std::string GateStepCsv() {
  return FracGateStepCsv({0.55, 6.0, 3.0, 0.7, 15.0, 40.0}, {2400, 40, 0.15, 0.15, 7});
}

class ReportCli : public ::testing::Test {
 protected:
  void SetUp() override {
    // Suite and test: two suites have tests of the same name, and ctest runs them side by side.
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = TestDirectory(std::string(info->test_suite_name()) + "." + info->name());
  }

  // Runs the report into dir_/report and checks every linked figure; returns the page.
  std::string Report(const std::string& input, const std::string& args,
                     const std::set<std::string>& expected_images) {
    const ProgramRun run = RunProgram(CanalidProgram() + " report --input " + input + " --out " +
                                          (dir_ / "report").string() + " " + args,
                                      dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    // Not a terminal here: no progress line.
    EXPECT_EQ(run.err, "");
    std::string html = ReadFile(dir_ / "report" / "index.html");
    const std::vector<std::string> links = ImageLinks(html);
    EXPECT_EQ(std::set<std::string>(links.begin(), links.end()), expected_images);
    for (const std::string& link : links) {
      const auto path = dir_ / "report" / link;
      EXPECT_TRUE(std::filesystem::exists(path)) << link;
      if (!std::filesystem::exists(path)) continue;
      EXPECT_GT(std::filesystem::file_size(path), kMinPngBytes) << link;
      const PngFacts png = InspectPng(path);
      EXPECT_TRUE(png.signature) << link;
      EXPECT_EQ(png.width, kWidth) << link;
      EXPECT_EQ(png.height, kHeight) << link;
      // Curves drawn: a frame with axes, grid, title and key but no data (plot NaN) has
      // 0.01 % coloured pixels, the sparsest figure here (a dashed fit under the measured
      // line) 0.2 %.
      EXPECT_GT(png.coloured_fraction, 0.001) << link;
    }
    // Self-contained: no scripts, nothing fetched from elsewhere.
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find("http"), std::string::npos);
    return html;
  }

  nlohmann::json Identify(const std::string& input, const std::string& args) {
    const ProgramRun run =
        RunProgram(CanalidProgram() + " identify --input " + input + " " + args, dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json();
  }

  // The table row of `kind` shows identify's metrics (and delay and area where the model has
  // them) for the same data and options.
  void ExpectTableMatchesIdentify(const std::string& html, const std::string& input,
                                  const std::string& kind, const std::string& args) {
    const nlohmann::json model = Identify(input, "--model " + kind + " " + args);
    for (const char* metric : {"fit_percent", "rmse", "mae", "norm_error"}) {
      EXPECT_EQ(Cell(html, kind, metric), SixDigits(model["metrics"][metric].get<double>()))
          << kind << " " << metric;
    }
    for (const char* key : {"delay_s", "area_m2"}) {
      EXPECT_EQ(Cell(html, kind, key),
                model.contains(key) ? SixDigits(model[key].get<double>()) : std::string())
          << kind << " " << key;
    }
  }

  std::filesystem::path dir_;
};

std::set<std::string> ModelImages(const std::vector<std::string>& kinds) {
  std::set<std::string> images = {"inputs.png", "outputs.png", "steps.png"};
  for (const auto& k : kinds) {
    images.insert({"fit_" + k + ".png", "residuals_" + k + ".png", "acf_" + k + ".png"});
  }
  return images;
}

TEST_F(ReportCli, CanalPrbsRecordWithFourKinds) {
  const std::string args = "--u q_in --y level --nk 12";
  const std::string html = Report(kPrbs, "--model id arx foptd frac-ss " + args,
                                  ModelImages({"id", "arx", "foptd", "frac-ss"}));
  for (const char* kind : {"id", "arx", "foptd", "frac-ss"}) {
    ExpectTableMatchesIdentify(html, kPrbs, kind, args);
  }
  // The ID model's unit step of q_in: nothing before the delay, then the level ramps at
  // 1/A m/s (y(s) = e^{-tau s}/(A s) q_in(s)); p21's jump is a constant, so slopes are exact
  // up to the data file's 10 digits.
  const nlohmann::json id = Identify(kPrbs, "--model id");
  const double area = id["area_m2"].get<double>();
  const double delay = id["delay_s"].get<double>();
  const auto step = ReadData(dir_ / "report" / "gnuplot" / "step_id_0.dat");
  ASSERT_GT(step.size(), 100u);
  for (const auto& row : step) {
    if (row[0] < delay) {
      EXPECT_NEAR(row[1], 0.0, 1e-12) << "t = " << row[0];
    }
  }
  const auto& last = step.back();
  const auto& earlier = step[step.size() - 101];
  EXPECT_NEAR((last[1] - earlier[1]) / (last[0] - earlier[0]) * area, 1.0, 1e-7);
  // The residuals' autocorrelation starts at exactly 1 (lag 0) and its band is 2.576/sqrt(N)
  // over the N simulated samples (841 rows from fit_from_sample on).
  const auto acf = ReadData(dir_ / "report" / "gnuplot" / "acf_id.dat");
  ASSERT_EQ(acf.size(), 26u);
  EXPECT_NEAR(acf[0][1], 1.0, 1e-9);
  const auto fit = ReadData(dir_ / "report" / "gnuplot" / "fit_id.dat");
  const std::string script = ReadFile(dir_ / "report" / "gnuplot" / "acf_id.gp");
  std::smatch band;
  ASSERT_TRUE(
      std::regex_search(script, band, std::regex("'residual autocorrelation', ([-0-9.e]+)")));
  // z_0.995 = 2.5758293035489 (standard normal tables).
  EXPECT_NEAR(std::stod(band[1]) * std::sqrt(static_cast<double>(fit.size())), 2.5758293035489,
              1e-6);
  // The model files are the identify JSON, ready for `canalid simulate`.
  const nlohmann::json saved =
      nlohmann::json::parse(ReadFile(dir_ / "report" / "models" / "id.json"));
  EXPECT_EQ(saved["area_m2"], id["area_m2"]);
}

// --model idz with --canal/--pool: beside the identified model, the IDZ model of the pool's
// geometry (canalid theory at the record's mean inflow, about 10 m3/s): its step in the step
// figure, (t - tau)/A + p21 after the delay, and both frequency responses in bode_idz.png, whose
// data follow |p21(jw)| = |1/(A j w) + p21| of each model.
TEST_F(ReportCli, IdzBesideTheGeometrysModel) {
  const std::string canal = std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal2.toml";
  std::set<std::string> images = ModelImages({"idz"});
  images.insert("bode_idz.png");
  Report(kPrbs, "--model idz --canal " + canal + " --pool 2", images);
  std::ostringstream flow;  // the record's mean inflow, which the report uses
  flow.precision(17);
  flow << drivers::CsvTable::Read(kPrbs).Column("q_in").mean();
  const ProgramRun theory_run = RunProgram(
      CanalidProgram() + " theory --canal " + canal + " --pool 2 --flow " + flow.str(), dir_);
  ASSERT_EQ(theory_run.exit_code, 0) << theory_run.err;
  const auto theory = nlohmann::json::parse(theory_run.out);
  const double area = theory["area_m2"], delay = theory["delay_s"], p21 = theory["p21_s_per_m2"];
  const auto step = ReadData(dir_ / "report" / "gnuplot" / "step_idz_1.dat");
  ASSERT_GT(step.size(), 100u);
  for (const auto& row : step) {
    const double expected = row[0] < delay ? 0.0 : (row[0] - delay) / area + p21;
    EXPECT_NEAR(row[1], expected, 1e-9 * (1.0 + std::abs(expected))) << "t = " << row[0];
  }
  const auto bode = ReadData(dir_ / "report" / "gnuplot" / "bode_idz_1.dat");
  ASSERT_EQ(bode.size(), 200u);
  for (const auto& row : {bode.front(), bode.back()}) {
    const double w = row[0];
    EXPECT_NEAR(row[1], std::hypot(1.0 / (area * w), p21), 1e-8 * row[1]) << "w = " << w;
  }
  EXPECT_NEAR(bode.front()[0], 0.01 / delay, 1e-9 / delay);
  EXPECT_NEAR(bode.back()[0], std::min(100.0 / delay, M_PI / 60.0), 1e-9);
  // The identified model's curve is the other one.
  const nlohmann::json idz = Identify(kPrbs, "--model idz");
  const auto identified = ReadData(dir_ / "report" / "gnuplot" / "bode_idz_0.dat");
  ASSERT_EQ(identified.size(), 200u);
  EXPECT_NEAR(identified.back()[1],
              std::hypot(1.0 / (idz["area_m2"].get<double>() * identified.back()[0]),
                         idz["p21_s_per_m2"].get<double>()),
              1e-8);
}

TEST_F(ReportCli, FractionalGateStepRecord) {
  WriteFile(dir_ / "step.csv", GateStepCsv());
  const std::string input = (dir_ / "step.csv").string();
  const std::string args = "--u gate --y level";
  const std::string html = Report(input, "--model foptd,soptd,frac-foptd " + args,
                                  ModelImages({"foptd", "soptd", "frac-foptd"}));
  for (const char* kind : {"foptd", "soptd", "frac-foptd"}) {
    ExpectTableMatchesIdentify(html, input, kind, args);
  }
  // The frac-foptd unit step against the exact response K (1 - E_alpha(-(t - tau)^alpha / T))
  // of the identified parameters: the report simulates with the Oustaloup filter, so they
  // agree to the approximation's accuracy (0.03 % of K measured here; 0.2 % allowed).
  const nlohmann::json m = Identify(input, "--model frac-foptd " + args);
  const double k = m["gain"], t = m["time_constant_s"], tau = m["delay_s"], a = m["alpha"];
  const auto step = ReadData(dir_ / "report" / "gnuplot" / "step_frac-foptd_0.dat");
  ASSERT_GT(step.size(), 1000u);
  double worst = 0.0;
  for (const auto& row : step) {
    const double exact = k * FracUnitStep(a, t, row[0] - tau);
    worst = std::max(worst, std::abs(row[1] - exact));
  }
  EXPECT_LT(worst, 0.002 * k);
}

TEST_F(ReportCli, LpvParametersAgainstTheSchedule) {
  WriteFile(dir_ / "lpv.csv", LpvCsv(3, 1e-3));
  const std::string input = (dir_ / "lpv.csv").string();
  const std::string args =
      "--local arx --schedule upstream --bands 1.0,1.2,1.4,1.6,1.8,2.0 --u gate --y level";
  std::set<std::string> images = ModelImages({"lpv"});
  images.insert({"lpv_0_a1.png", "lpv_1_b1.png", "lpv_2_nk.png"});
  const std::string html = Report(input, "--model lpv " + args, images);
  ExpectTableMatchesIdentify(html, input, "lpv", args);
  // The local estimates plotted are the model's, at the operating points' mean theta.
  const nlohmann::json m = Identify(input, "--model lpv " + args);
  const auto local = ReadData(dir_ / "report" / "gnuplot" / "lpv_0_a1_local.dat");
  ASSERT_EQ(local.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_NEAR(local[i][0], m["metrics_per_band"][i]["theta_mean"].get<double>(), 1e-9);
    EXPECT_NEAR(local[i][1], m["metrics_per_band"][i]["local_params"]["a1"].get<double>(), 1e-9);
  }
  // Step responses at every operating point settle at the true plant's static gain
  // b1/(1 + a1) at that theta (identification error: within 3 %).
  for (std::size_t i = 0; i < kLpvThetas.size(); ++i) {
    const auto step =
        ReadData(dir_ / "report" / "gnuplot" / ("step_lpv_" + std::to_string(i) + ".dat"));
    ASSERT_FALSE(step.empty());
    const double gain = Quadratic(kLpvB1, kLpvThetas[i]) / (1.0 + Quadratic(kLpvA1, kLpvThetas[i]));
    EXPECT_NEAR(step.back()[1] / gain, 1.0, 0.03) << "theta " << kLpvThetas[i];
  }
}

TEST_F(ReportCli, BadCsvIsExit2WithTheLocation) {
  WriteFile(dir_ / "bad.csv", "time_s,q_in,q_out,level\n0,10,10,2.1\n60,9.2,10,abc\n");
  const ProgramRun run =
      RunProgram(CanalidProgram() + " report --model id --input " + (dir_ / "bad.csv").string() +
                     " --out " + (dir_ / "r").string(),
                 dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("bad.csv:3: column 'level': 'abc' is not a number"), std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "r" / "index.html"));
}

TEST_F(ReportCli, MissingOrUnknownModelKindIsExit2) {
  const std::string base =
      CanalidProgram() + " report --input " + kPrbs + " --out " + (dir_ / "r").string();
  ProgramRun run = RunProgram(base, dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("no model kind: give --model KIND"), std::string::npos) << run.err;
  run = RunProgram(base + " --model id,idw", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("idw not in {id,idz,arx,foptd,soptd,frac-foptd,frac-ss,lpv}"),
            std::string::npos)
      << run.err;
  // A kind whose columns are not in the record names the kind and the columns there are.
  run = RunProgram(base + " --model foptd", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--model foptd: " + kPrbs + ": no column 'u'"), std::string::npos)
      << run.err;
}

TEST_F(ReportCli, MissingOrFailingGnuplotIsExit1) {
  const std::string base =
      CanalidProgram() + " report --model id --input " + kPrbs + " --out " + (dir_ / "r").string();
  ProgramRun run = RunProgram(base + " --gnuplot /nonexistent/gnuplot", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("cannot run '/nonexistent/gnuplot': No such file or directory"),
            std::string::npos)
      << run.err;
  WriteFile(dir_ / "broken-gnuplot", "#!/bin/sh\necho 'line 3: unknown terminal' >&2\nexit 3\n");
  std::filesystem::permissions(dir_ / "broken-gnuplot", std::filesystem::perms::owner_all);
  run = RunProgram(base + " --gnuplot " + (dir_ / "broken-gnuplot").string(), dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("failed with exit status 3 on"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("line 3: unknown terminal"), std::string::npos) << run.err;
}

TEST_F(ReportCli, ProgressOnATerminalOnly) {
  ASSERT_TRUE(std::filesystem::exists("/usr/bin/script"))
      << "no script(1) for a pty (Debian bsdutils)";
  // script(1) runs the report on a pseudo-terminal and copies what it wrote.
  const ProgramRun run =
      RunProgram("/usr/bin/script -qec '" + CanalidProgram() + " report --model id --input " +
                     kPrbs + " --out " + (dir_ / "r").string() + "' /dev/null",
                 dir_);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("canalid report: identifying id (1/1)..."), std::string::npos);
  EXPECT_NE(run.out.find("canalid report: plotting 6/6..."), std::string::npos);
}

}  // namespace
}  // namespace canalid::testing
