#include "daemon/canalid/report_input.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include "daemon/canalid/input_error.h"
#include "daemon/canalid/log_export.h"
#include "daemon/canalid/table_columns.h"
#include "daemon/config/config_loader.h"
#include "drivers/lcm/log_reader.h"

namespace canalid::cli {
namespace {

ReportInput FromLog(const std::string& path, const ReportLogOptions& options) {
  std::optional<config::DaemonConfig> config;
  drivers::LogScanOptions scan;
  if (!options.config.empty()) {
    try {
      config = daemon::LoadDaemonConfig(options.config);
    } catch (const daemon::ConfigError& e) {
      throw InputError(std::string("--config: ") + e.what());
    }
    scan.prefix = config->lcm.channel_prefix;
  }
  LogExporter exporter(options.data_dir, config, options.reach, {}, path);
  OnlineModelRecorder recorder(exporter);
  drivers::LogScanResult result;
  try {
    result = drivers::ScanCanalidLog(path, scan, recorder);
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  exporter.Finish();
  if (result.end == drivers::LogEnd::kCorrupt) throw InputError(result.problem);
  if (!exporter.has_config()) {
    throw InputError(path +
                     ": no canalid configuration message in the log; give the daemon's "
                     "configuration with --config");
  }
  std::string reach = options.reach;
  if (reach.empty()) {
    std::string all;
    for (const auto& [name, channels] : exporter.reach_channels()) {
      all += (all.empty() ? "" : ", ") + name;
      reach = name;
    }
    if (exporter.reach_channels().size() != 1) {
      throw InputError(path + ": " +
                       (all.empty() ? std::string("no samples of a configured reach")
                                    : "several reaches (" + all + "): choose one with --reach"));
    }
  }
  const auto channels = exporter.reach_channels().find(reach);
  if (channels == exporter.reach_channels().end())
    throw InputError("--reach " + reach + ": no samples of this reach in " + path);
  ReportInput input{
      ReadTable((std::filesystem::path(options.data_dir) / (reach + ".csv")).string()),
      channels->second, recorder.Trajectories(reach)};
  return input;
}

}  // namespace

bool IsLcmLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 4> head{};
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size())) return false;
  const std::uint32_t word = (std::uint32_t{head[0]} << 24) | (std::uint32_t{head[1]} << 16) |
                             (std::uint32_t{head[2]} << 8) | std::uint32_t{head[3]};
  return word == drivers::LogReader::kSyncWord;
}

ReportInput LoadReportInput(const std::string& path, const ReportLogOptions& log) {
  if (IsLcmLog(path)) return FromLog(path, log);
  if (!log.reach.empty() || !log.config.empty())
    throw InputError(path + ": --reach and --config apply to an LCM log input, not to a CSV");
  return ReportInput{ReadTable(path), std::nullopt, {}};
}

IdentifyOptions WithReachColumns(IdentifyOptions options,
                                 const std::array<std::string, 4>& channels) {
  const IdentifyOptions defaults;
  if (options.qin == defaults.qin) options.qin = channels[0];
  if (options.qout == defaults.qout) options.qout = channels[1];
  if (options.level == defaults.level) options.level = channels[2];
  if (options.u == defaults.u) options.u = channels[3];
  if (options.y == defaults.y) options.y = channels[2];
  return options;
}

}  // namespace canalid::cli
