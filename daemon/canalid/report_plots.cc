#include "daemon/canalid/report_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "daemon/canalid/child_process.h"
#include "daemon/canalid/table_columns.h"

namespace canalid::cli {
namespace {

constexpr const char* kTerminal =
    "set terminal pngcairo size 960,480 noenhanced font 'sans,10' linewidth 1.2\n";
constexpr const char* kMeasuredStyle = "lw 2 lc rgb '#1f1f1f'";
// Distinct colours for the models, in --model order.
constexpr const char* kColours[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd",
                                    "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

const char* Colour(std::size_t i) { return kColours[i % (sizeof kColours / sizeof *kColours)]; }

// A gnuplot single-quoted string: a quote is written twice.
std::string Quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) {
    quoted += c;
    if (c == '\'') quoted += '\'';
  }
  return quoted + "'";
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "NaN";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", v);
  return buffer;
}

// Time in the unit that suits the record: seconds up to 20 min, minutes up to 5 h, then hours.
struct TimeAxis {
  double divisor = 1.0;
  std::string unit = "s";
  std::string Using(int column) const {
    return "($1/" + Number(divisor) + "):" + std::to_string(column);
  }
};

TimeAxis AxisFor(double duration_s) {
  if (duration_s > 5 * 3600.0) return {3600.0, "h"};
  if (duration_s > 20 * 60.0) return {60.0, "min"};
  return {};
}

void WriteData(const std::filesystem::path& path, const std::vector<std::string>& names,
               const std::vector<Eigen::VectorXd>& columns) {
  std::ofstream out(path, std::ios::trunc);
  out << "#";
  for (const auto& name : names) out << " " << name;
  out << "\n";
  Eigen::Index rows = 0;
  for (const auto& c : columns) rows = std::max(rows, c.size());
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      out << (c ? " " : "") << (r < columns[c].size() ? Number(columns[c](r)) : "NaN");
    }
    out << "\n";
  }
  if (!out.flush()) throw ToolError(path.string() + ": cannot write the plot data");
}

// Collects one figure: its data files and script under dir/gnuplot.
class PlotWriter {
 public:
  explicit PlotWriter(std::filesystem::path dir) : dir_(std::move(dir)) {}

  std::string Data(const std::string& name, const std::vector<std::string>& names,
                   const std::vector<Eigen::VectorXd>& columns) {
    WriteData(dir_ / "gnuplot" / (name + ".dat"), names, columns);
    return Quote("gnuplot/" + name + ".dat");
  }

  void Add(const std::string& name, const std::string& section, const std::string& model,
           const std::string& title, const std::string& body) {
    Plot plot{name + ".png", "gnuplot/" + name + ".gp", section, model, title};
    std::ofstream out(dir_ / plot.script, std::ios::trunc);
    out << "# " << title << "\n"
        << kTerminal << "set output " << Quote(plot.image) << "\n"
        << "set title " << Quote(title) << "\nset grid\nset key top right\n"
        << body;
    if (!out.flush()) throw ToolError((dir_ / plot.script).string() + ": cannot write");
    plots_.push_back(plot);
  }

  std::vector<Plot> Take() { return std::move(plots_); }

 private:
  std::filesystem::path dir_;
  std::vector<Plot> plots_;
};

// The columns every model read, in --model order without repeats.
std::vector<std::string> Collect(const std::vector<ModelAnalysis>& models, const std::string& key) {
  std::vector<std::string> names;
  auto add = [&names](const std::string& name) {
    if (!name.empty() && std::find(names.begin(), names.end(), name) == names.end())
      names.push_back(name);
  };
  for (const auto& m : models) {
    if (!m.model.contains(key)) continue;
    const nlohmann::json& v = m.model.at(key);
    if (v.is_string()) add(v.get<std::string>());
    if (v.is_array()) {
      for (const auto& item : v) {
        if (item.is_string()) add(item.get<std::string>());
      }
    }
  }
  return names;
}

// Several columns of one data file as one plot command: the first series names the file, the
// others refer to it as ''.
std::string PlotCommand(const std::string& data, const std::vector<std::string>& series) {
  std::string command = "plot ";
  for (std::size_t i = 0; i < series.size(); ++i) {
    command += (i ? ", ''" : data) + " " + series[i];
  }
  return command + "\n";
}

void RecordPlots(PlotWriter& w, const drivers::CsvTable& table,
                 const std::vector<ModelAnalysis>& models, const TimeAxis& axis) {
  const std::vector<std::string> inputs = Collect(models, "inputs");
  const std::vector<std::string> schedules = Collect(models, "schedule");
  std::vector<std::string> names = {"time_s"};
  std::vector<Eigen::VectorXd> columns = {table.time_s()};
  std::vector<std::string> series;
  for (const auto& name : inputs) {
    names.push_back(name);
    columns.push_back(RequireColumn(table, name));
    series.push_back("using " + axis.Using(static_cast<int>(names.size())) +
                     " with steps lw 1.5 lc rgb '" + Colour(series.size()) + "' title " +
                     Quote(name));
  }
  for (const auto& name : schedules) {
    names.push_back(name);
    columns.push_back(RequireColumn(table, name));
    series.push_back("using " + axis.Using(static_cast<int>(names.size())) +
                     " axes x1y2 with lines dt 2 lw 1.5 lc rgb '#555555' title " +
                     Quote(name + " (schedule, right axis)"));
  }
  if (!series.empty()) {
    std::ostringstream plot;
    plot << "set xlabel " << Quote("time (" + axis.unit + ")")
         << "\nset ylabel 'input'\nset key below\nset autoscale xfix\n";
    if (!schedules.empty()) {
      plot << "set y2label " << Quote("schedule " + schedules.front()) << "\nset y2tics\n";
    }
    plot << PlotCommand(w.Data("inputs", names, columns), series);
    w.Add("inputs", "record", "", "Inputs (excitation) of " + table.source(), plot.str());
  }

  names = {"time_s"};
  columns = {table.time_s()};
  series.clear();
  for (const auto& name : Collect(models, "output")) {
    names.push_back(name);
    columns.push_back(RequireColumn(table, name));
    series.push_back("using " + axis.Using(static_cast<int>(names.size())) +
                     " with lines lw 1.5 lc rgb '" + Colour(series.size()) + "' title " +
                     Quote(name));
  }
  if (!series.empty()) {
    std::ostringstream out;
    out << "set xlabel " << Quote("time (" + axis.unit + ")")
        << "\nset ylabel 'output'\nset key below\nset autoscale xfix\n"
        << PlotCommand(w.Data("outputs", names, columns), series);
    w.Add("outputs", "record", "", "Measured output of " + table.source(), out.str());
  }
}

void ModelPlots(PlotWriter& w, const ModelAnalysis& m, std::size_t index, const TimeAxis& axis,
                double sample_time_s) {
  if (m.simulated.size() == 0) return;
  const std::string colour = Colour(index);
  std::ostringstream fit;
  fit << "set autoscale xfix\nset xlabel " << Quote("time (" + axis.unit + ")") << "\nset ylabel "
      << Quote(m.output) << "\nplot "
      << w.Data("fit_" + m.kind, {"time_s", "measured", "simulated"},
                {m.time_s, m.measured, m.simulated})
      << " using " << axis.Using(2) << " with lines " << kMeasuredStyle << " title "
      << Quote("measured " + m.output) << ", '' using " << axis.Using(3)
      << " with lines dt 2 lw 2 lc rgb '" << colour << "' title "
      << Quote("simulated (" + m.kind + ")") << "\n";
  w.Add("fit_" + m.kind, "fit", m.kind,
        m.kind + ": measured (solid) and simulated (dashed) " + m.output, fit.str());

  std::ostringstream res;
  res << "set autoscale xfix\nset xlabel " << Quote("time (" + axis.unit + ")") << "\nset ylabel "
      << Quote("residual " + m.output) << "\nplot "
      << w.Data("residuals_" + m.kind, {"time_s", "residual"}, {m.time_s, m.residual}) << " using "
      << axis.Using(2) << " with lines lw 1.5 lc rgb '" << colour
      << "' title 'measured - simulated', 0 with lines lc rgb '#888888' notitle\n";
  w.Add("residuals_" + m.kind, "residuals", m.kind, m.kind + ": residuals", res.str());

  if (m.autocorrelation.size() == 0) return;
  const Eigen::Index lags = m.autocorrelation.size();
  std::ostringstream acf;
  acf << "set xlabel " << Quote("lag (samples of " + Number(sample_time_s) + " s)")
      << "\nset ylabel 'autocorrelation'\nset xrange [-0.5:"
      << Number(static_cast<double>(lags) - 0.5) << "]\n"
      << "set yrange [-1.05:1.05]\nplot "
      << w.Data("acf_" + m.kind, {"lag", "r"},
                {Eigen::VectorXd::LinSpaced(lags, 0.0, static_cast<double>(lags - 1)),
                 m.autocorrelation})
      << " using 1:2 with impulses lw 4 lc rgb '" << colour
      << "' title 'residual autocorrelation', " << Number(m.band_99)
      << " with lines dt 2 lw 1.5 lc rgb '#555555' title '99 % band (white noise)', "
      << Number(-m.band_99) << " with lines dt 2 lw 1.5 lc rgb '#555555' notitle\n";
  w.Add("acf_" + m.kind, "residuals", m.kind,
        m.kind + ": residual autocorrelation with the 99 % confidence band", acf.str());
}

// How much of a step response to show: twice its 2 % settling time (at least 20 samples), all
// of it when it does not settle (an integrator's ramp).
double StepHorizon(const StepCurve& s, double sample_time_s) {
  const Eigen::Index n = s.response.size();
  if (n == 0) return 0.0;
  const double final = s.response(n - 1);
  Eigen::Index last_outside = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (std::abs(s.response(k) - final) > 0.02 * std::abs(final)) last_outside = k;
  }
  return std::min(s.time_s(n - 1), std::max(2.0 * s.time_s(last_outside), 20.0 * sample_time_s));
}

void StepPlot(PlotWriter& w, const std::vector<ModelAnalysis>& models, double sample_time_s) {
  double horizon_s = 0.0;
  for (const auto& m : models) {
    for (const auto& s : m.steps) horizon_s = std::max(horizon_s, StepHorizon(s, sample_time_s));
  }
  if (horizon_s <= 0.0) return;
  const TimeAxis axis = AxisFor(horizon_s);
  std::ostringstream plot;
  plot << "set xlabel " << Quote("time since the step (" + axis.unit + ")")
       << "\nset ylabel 'output change per unit step'\nset key outside right top\n"
       << "set xrange [" << Number(-sample_time_s / axis.divisor) << ":"
       << Number(horizon_s / axis.divisor) << "]\nplot ";
  std::string series;
  int n = 0;
  for (std::size_t i = 0; i < models.size(); ++i) {
    for (std::size_t j = 0; j < models[i].steps.size(); ++j) {
      const StepCurve& s = models[i].steps[j];
      const std::string data = w.Data("step_" + models[i].kind + "_" + std::to_string(j),
                                      {"time_s", "response"}, {s.time_s, s.response});
      series += std::string(n++ ? ", " : "") + data + " using " + axis.Using(2) +
                " with lines lw 2 lc rgb '" + Colour(i) + "'" +
                (j ? " dt " + std::to_string(j + 1) : "") + " title " + Quote(s.label);
    }
  }
  plot << series << "\n";
  w.Add("steps", "steps", "", "Step responses of the identified models", plot.str());
}

// A model's frequency responses beside each other: gain (log-log) over phase.
void BodePlot(PlotWriter& w, const ModelAnalysis& m) {
  if (m.bode.empty()) return;
  std::ostringstream plot;
  std::string gain = "plot ", phase = "plot ";
  for (std::size_t j = 0; j < m.bode.size(); ++j) {
    const BodeCurve& c = m.bode[j];
    const std::string data =
        w.Data("bode_" + m.kind + "_" + std::to_string(j), {"omega_rad_s", "gain", "phase_deg"},
               {c.omega_rad_s, c.gain, c.phase_deg});
    const std::string style = " with lines lw 2 lc rgb '" + std::string(Colour(j)) + "'" +
                              (j ? " dt 2" : "") + " title " + Quote(c.label);
    const char* separator = j ? ", " : "";
    gain.append(separator).append(data).append(" using 1:2").append(style);
    phase.append(separator).append(data).append(" using 1:3").append(style);
  }
  plot << "set multiplot layout 2,1\nset logscale x\nset key outside right top\n"
       << "set logscale y\nset ylabel 'gain (level per inflow)'\nunset xlabel\n"
       << gain << "\nunset logscale y\nset ylabel 'phase (deg)'\n"
       << "set xlabel 'frequency (rad/s)'\n"
       << phase << "\nunset multiplot\n";
  w.Add("bode_" + m.kind, "fit", m.kind,
        m.kind +
            ": frequency response of the level to the inflow, identified and from the "
            "geometry",
        plot.str());
}

void LpvPlots(PlotWriter& w, const ModelAnalysis& m) {
  const LpvCurves& c = m.lpv;
  std::string edges;
  for (double e : c.band_edges) {
    edges += "set arrow from " + Number(e) + ", graph 0 to " + Number(e) +
             ", graph 1 nohead dt 3 lc rgb '#999999'\n";
  }
  for (std::size_t j = 0; j < c.parameters.size(); ++j) {
    const auto col = static_cast<Eigen::Index>(j);
    const std::string& p = c.parameters[j];
    const std::string name = "lpv_" + std::to_string(j) + "_" + p;
    std::ostringstream plot;
    plot << edges << "set xlabel " << Quote(c.schedule + " (scheduling variable)")
         << "\nset ylabel " << Quote(p)
         << "\nset offsets graph 0, graph 0, graph 0.1, graph 0.1\nplot "
         << w.Data(name + "_polynomial", {c.schedule, p}, {c.theta_grid, c.polynomial.col(col)})
         << " using 1:2 with lines lw 2 lc rgb '#1f77b4' title "
         << Quote("LPV polynomial, degree " + std::to_string(m.model.value("degree", 0))) << ", "
         << w.Data(name + "_local", {c.schedule, p}, {c.theta_points, c.local.col(col)})
         << " using 1:2 with points pt 7 ps 1.6 lc rgb '#d62728' title 'local estimates'\n";
    w.Add(name, "lpv", m.kind, "LPV parameter " + p + " against " + c.schedule, plot.str());
  }
}

// One figure per online model: a panel per parameter, the estimate over time and its +-2 sigma
// band (where the daemon published a standard deviation).
void OnlinePlots(PlotWriter& w, const OnlineTrajectory& t) {
  if (t.time_s.size() == 0 || t.names.empty()) return;
  const TimeAxis axis = AxisFor(t.time_s(t.time_s.size() - 1) - t.time_s(0));
  const std::string name = "online_" + t.kind;
  std::vector<std::string> columns{"time"};
  std::vector<Eigen::VectorXd> data{t.time_s / axis.divisor};
  for (std::size_t j = 0; j < t.names.size(); ++j) {
    const auto c = static_cast<Eigen::Index>(j);
    columns.insert(columns.end(), {t.names[j], t.names[j] + "_low", t.names[j] + "_high"});
    data.push_back(t.values.col(c));
    data.push_back(t.values.col(c) - 2.0 * t.std_devs.col(c));
    data.push_back(t.values.col(c) + 2.0 * t.std_devs.col(c));
  }
  const std::string file = w.Data(name, columns, data);
  std::ostringstream plot;
  const std::size_t panels = t.names.size();
  // One panel per parameter, stacked: the figure grows with them.
  plot << "set terminal pngcairo size 960," << 160 * panels + 80
       << " noenhanced font 'sans,10' linewidth 1.2\nset output " << Quote(name + ".png")
       << "\nset multiplot layout " << panels << ",1 title "
       << Quote("Online " + t.kind + " estimates as the daemon published them")
       << "\nunset title\nset key top left\n";
  for (std::size_t j = 0; j < panels; ++j) {
    const std::size_t col = 2 + 3 * j;
    plot << "set ylabel " << Quote(t.names[j]) << "\n"
         << (j + 1 == panels ? "set xlabel " + Quote("time (" + axis.unit + ")") + "\n" : "")
         << "plot " << file << " using 1:" << col + 1 << ":" << col + 2
         << " with filledcurves fc rgb '#c6dbef' fs solid 0.6 title '+-2 sigma', '' using 1:" << col
         << " with lines lw 2 lc rgb " << Quote(Colour(j)) << " title " << Quote(t.names[j])
         << "\n";
  }
  plot << "unset multiplot\n";
  w.Add(name, "online", t.kind, "Online " + t.kind + " estimates as the daemon published them",
        plot.str());
}

}  // namespace

std::vector<Plot> WritePlotScripts(const drivers::CsvTable& table,
                                   const std::vector<ModelAnalysis>& models,
                                   const std::filesystem::path& dir,
                                   const std::vector<OnlineTrajectory>& online) {
  const Eigen::VectorXd t = table.time_s();
  const TimeAxis axis = AxisFor(t(t.size() - 1) - t(0));
  PlotWriter w(dir);
  RecordPlots(w, table, models, axis);
  for (std::size_t i = 0; i < models.size(); ++i) {
    ModelPlots(w, models[i], i, axis, table.sample_time_s());
  }
  StepPlot(w, models, table.sample_time_s());
  for (const auto& m : models) {
    BodePlot(w, m);
    if (m.has_lpv) LpvPlots(w, m);
  }
  for (const auto& trajectory : online) OnlinePlots(w, trajectory);
  return w.Take();
}

void RenderPlots(const std::vector<Plot>& plots, const std::string& gnuplot,
                 const std::filesystem::path& dir,
                 const std::function<void(std::size_t, std::size_t)>& before_each) {
  for (std::size_t i = 0; i < plots.size(); ++i) {
    before_each(i, plots.size());
    const Plot& p = plots[i];
    std::filesystem::remove(dir / p.image);
    const std::filesystem::path log =
        dir / std::filesystem::path(p.script).replace_extension(".log");
    const ChildResult result = RunChild(gnuplot, {p.script}, dir, log);
    if (result.exit_code != 0) {
      throw ToolError(
          "gnuplot ('" + gnuplot + "') failed with exit status " +
          std::to_string(result.exit_code) + " on " + (dir / p.script).string() +
          (result.error_text.empty() ? std::string(" (no message)") : ":\n" + result.error_text));
    }
    if (!std::filesystem::exists(dir / p.image) || std::filesystem::file_size(dir / p.image) == 0) {
      throw ToolError("gnuplot ('" + gnuplot + "') wrote no image " + (dir / p.image).string() +
                      " from " + (dir / p.script).string() + ": " + result.error_text);
    }
  }
}

}  // namespace canalid::cli
