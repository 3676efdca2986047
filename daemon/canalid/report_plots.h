#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "daemon/canalid/report_analysis.h"
#include "daemon/canalid/report_online.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// One figure of the report: a PNG made by gnuplot from a script and data files kept in
/// DIR/gnuplot/ (so `cd DIR && gnuplot gnuplot/NAME.gp` redraws it).
struct Plot {
  std::string image;    ///< file name in the report directory, e.g. "fit_arx.png"
  std::string script;   ///< relative to the report directory, e.g. "gnuplot/fit_arx.gp"
  std::string section;  ///< record, fit, residuals, steps or lpv
  std::string model;    ///< the model kind it shows, empty for the record and the steps
  std::string title;
};

/// Writes the data files and gnuplot scripts of every figure into dir/gnuplot (which must exist):
/// the inputs (PRBS/excitation, schedule) and the outputs over time; per simulated model the
/// measured and simulated output (solid and dashed, as the Arizona study's Figures 6-7), the
/// residuals and their autocorrelation with the 99 % band; the step responses of all models;
/// per LPV parameter its polynomial in theta with the local estimates; per online model of a log
/// (`online`) each parameter over time with its +-2 sigma band.
/// @throws ToolError if a file cannot be written.
std::vector<Plot> WritePlotScripts(const drivers::CsvTable& table,
                                   const std::vector<ModelAnalysis>& models,
                                   const std::filesystem::path& dir,
                                   const std::vector<OnlineTrajectory>& online = {});

/// Runs `gnuplot` (a program name or path) once per plot, in `dir`, with the plot's script as
/// its only argument; `before_each(i, n)` is called before plot i of n.  gnuplot's stderr is kept
/// in dir/gnuplot/NAME.log.
/// @throws ToolError if gnuplot cannot be started, exits non-zero (the message gives the exit
///         status and its stderr) or leaves no image.
void RenderPlots(const std::vector<Plot>& plots, const std::string& gnuplot,
                 const std::filesystem::path& dir,
                 const std::function<void(std::size_t, std::size_t)>& before_each);

}  // namespace canalid::cli
