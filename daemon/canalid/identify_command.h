#pragma once
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/linear/arx.h"

namespace CLI {
class App;
}

namespace canalid::drivers {
class CsvTable;
}

namespace canalid::cli {

/// Everything `canalid identify` takes from the command line.
struct IdentifyOptions {
  std::string model;
  std::string input;
  std::string out;  ///< also write the JSON here when not empty
  bool pretty = false;
  // id
  std::string qin = "q_in";
  std::string qout = "q_out";
  std::string level = "level";
  double max_delay_s = -1.0;
  std::string closed_loop = "auto";
  /// --p22: IDZ direct outflow gain, s/m2 (--online id: held; idz: the prior); < 0: not given
  double p22 = -1.0;
  double p22_std = -1.0;  ///< --p22-std (idz): the prior's std; < 0: 20 % of the prior
  std::string canal;      ///< --canal (idz): canal file whose --pool gives the p22 prior
  std::string pool;       ///< --pool (idz)
  bool keep_outliers = false;
  // arx, foptd, soptd
  std::string u = "u";
  std::string y = "y";
  int na = 2;
  std::string nb = "2";
  std::string nk = "1";
  bool detrend = false;
  // frac-foptd, frac-ss
  double alpha = 0.0;  ///< > 0: alpha held at this value (frac-foptd)
  int q = 0;           ///< commensurate order alpha = 1/q (frac-ss; 0 = the default 2)
  // lpv
  std::string local;
  std::string schedule;
  std::string bands;
  std::string bands_file;
  int degree = 2;
  int min_band_samples = 50;
  // --online
  bool online = false;
  double forgetting = 1.0;
  std::optional<double> initial_covariance;  ///< P0 = p0 I; none: the kind's default
  std::string method = "ud_directional";
  std::string trace;   ///< --trace OUT.csv
  std::string config;  ///< --config canalidd.toml: the reach's online settings and columns
  std::string reach;   ///< --reach NAME, with --config
  // --compare
  std::string compare;
  bool json = false;
};

/// Registers `identify` on the app; `exit_code` receives the result when it runs.
void AddIdentifyCommand(CLI::App& app, IdentifyOptions& options, int& exit_code);

/// The kinds `--model` accepts: id, idz, arx, foptd, soptd, frac-foptd, frac-ss, lpv.
const std::vector<std::string>& ModelKinds();

/// Registers the options that shape one identification (columns, orders, delays, fractional and
/// LPV settings: everything but --model, --input, --online, --compare and the output options) on
/// a command, so that `identify` and `report` take them alike.
void AddIdentifyModelOptions(CLI::App& cmd, IdentifyOptions& options);

/// @throws InputError if --p22, --p22-std or --canal are given but none of `kinds` uses them
/// (idz; --p22 also --model id --online).
void RequireIdzOptionsUsed(const IdentifyOptions& options, const std::vector<std::string>& kinds);

/// Identifies options.model (or the online estimator with options.online) on the table: the model
/// JSON of `canalid identify`, with "inputs", "output" and "input" (options.input, rows, sample
/// time) filled in.  @throws InputError on bad columns, options or data.
nlohmann::json IdentifyModel(const IdentifyOptions& options, const drivers::CsvTable& table);

/// One model kind each; they return the model JSON (docs/design.md keys).  @throws InputError.
nlohmann::json IdentifyId(const IdentifyOptions& options, const drivers::CsvTable& table);
nlohmann::json IdentifyArx(const IdentifyOptions& options, const drivers::CsvTable& table);
nlohmann::json IdentifyIdz(const IdentifyOptions& options, const drivers::CsvTable& table);
/// The idz p22 prior of --p22 or of --canal's --pool (the theory's low-frequency p22 at
/// `mean_inflow_m3s`), negative when neither is given; `prior` says where it came from (null
/// when none).  @throws InputError on both given, --p22-std alone, or a bad canal or pool.
double IdzP22Prior(const IdentifyOptions& options, double mean_inflow_m3s, nlohmann::json* prior);

/// The ARX problem as the options describe it: orders (one nb/nk for all inputs, or one each),
/// the output and input columns (inputs must move), optionally detrended.  @throws InputError.
/// `y` and `u` view the table's own columns when they can (one input, not detrended), else the
/// copies held here: the table must outlive the data, which can be moved but not copied.
struct ArxData {
  ArxData() = default;
  ArxData(const ArxData&) = delete;
  ArxData(ArxData&&) = default;  // the views keep pointing at the moved columns' memory
  ArxData& operator=(const ArxData&) = delete;
  ArxData& operator=(ArxData&&) = delete;  // a Map's assignment copies values, not the view

  std::vector<std::string> inputs;
  core::ArxOrders orders;
  Eigen::Map<const Eigen::VectorXd> y{nullptr, 0};
  Eigen::Map<const Eigen::MatrixXd> u{nullptr, 0, 0};
  nlohmann::json preprocessing;

 private:
  friend ArxData ReadArxData(const IdentifyOptions& options, const drivers::CsvTable& table);
  Eigen::VectorXd y_copy_;
  Eigen::MatrixXd u_copy_;
};
ArxData ReadArxData(const IdentifyOptions& options, const drivers::CsvTable& table);
/// foptd, soptd, frac-foptd, frac-ss: core::FitProcessBatch, as the daemon's batch_models.
nlohmann::json IdentifyProcessModel(const IdentifyOptions& options, const drivers::CsvTable& table);
nlohmann::json IdentifyLpv(const IdentifyOptions& options, const drivers::CsvTable& table);
/// `--online` with --model id or arx: the recursive estimator run sample by sample over the table,
/// its final snapshot in the batch keys plus `estimator` and `health`; --trace writes every step.
nlohmann::json IdentifyOnline(const IdentifyOptions& options, const drivers::CsvTable& table);
/// `--online` with --model arx and the flags: one RLS estimator (fixed-size up to 8 parameters)
/// over the ARX rows of the table, its final estimate in the batch arx keys.
nlohmann::json IdentifyOnlineArx(const IdentifyOptions& options, const drivers::CsvTable& table);
/// `--online` through the online model registry (the daemon's estimators): --model frac-foptd or
/// lpv with the flags (--u, --y, --nk as the known delay, --alpha, --schedule, --na, --nb), or
/// any registry kind with --config and --reach (the reach's settings, its channel names as
/// columns).  The final snapshot as drivers::OnlineModelJson, plus method and forgetting.
nlohmann::json IdentifyOnlineModel(const IdentifyOptions& options, const drivers::CsvTable& table);

/// `--compare`: fits every listed kind to every file of the glob in options.input and prints
/// the flume paper's Table 1 (mean, max, std of norm_error per model), or JSON with --json.
int RunCompare(const IdentifyOptions& options);

}  // namespace canalid::cli
