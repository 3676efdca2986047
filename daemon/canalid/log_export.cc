#include "daemon/canalid/log_export.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>

#include "core/system/errno_text.h"
#include "daemon/canalid/input_error.h"

namespace canalid::cli {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

void Cell(std::FILE* f, double value) { std::fprintf(f, ",%.17g", value); }

std::string MissingChannelMessage(const std::string& log_path, std::uint64_t offset,
                                  const std::string& channel, const std::string& reach,
                                  const std::string& plc) {
  return log_path + ": byte " + std::to_string(offset) + ": channel '" + channel + "' of reach '" +
         reach + "' is not in the samples of PLC '" + plc + "'";
}

}  // namespace

struct LogExporter::ReachFile {
  std::string name;
  std::string plc;
  std::vector<std::string> channels;  // inflow, outflow, level, actuator names, then extras
  std::vector<int> indices;           // in the PLC's samples; empty until its first sample
  double sample_time_s = 1.0;
  std::FILE* file = nullptr;
  std::optional<std::int64_t> last_sequence;
  double time_s = 0.0;
};

LogExporter::LogExporter(std::string dir, std::optional<config::DaemonConfig> config,
                         std::string reach, std::vector<std::string> model_parameters,
                         std::string log_path)
    : dir_(std::move(dir)),
      config_(std::move(config)),
      reach_filter_(std::move(reach)),
      model_parameters_(std::move(model_parameters)),
      log_path_(std::move(log_path)) {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) throw InputError("--out " + dir_ + ": cannot create: " + error.message());
}

LogExporter::~LogExporter() {
  for (std::FILE* f : files_) std::fclose(f);
}

std::FILE* LogExporter::Open(const std::string& name) {
  const std::string path = (std::filesystem::path(dir_) / name).string();
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw InputError(path + ": cannot create: " + core::ErrnoText(errno));
  files_.push_back(f);
  rows_[name] = 0;
  return f;
}

void LogExporter::OnConfig(const canalid::config_t& config, const drivers::LogEvent& event) {
  config_.OnConfig(config, event, log_path_);
}

void LogExporter::OnSample(const std::string& plc, const canalid::sample_t& sample,
                           const drivers::LogEvent& event) {
  if (!config_.config()) return;
  for (const config::ReachConfig& reach : config_.config()->reaches) {
    if (!reach_filter_.empty() && reach.name != reach_filter_) continue;
    if (config_.ReachPlc(reach) != plc) continue;
    ReachFile* file = nullptr;
    for (auto& r : reaches_) {
      if (r->name == reach.name) file = r.get();
    }
    if (file == nullptr) {
      auto r = std::make_unique<ReachFile>();
      r->name = reach.name;
      r->plc = plc;
      r->channels = {reach.inflow, reach.outflow, reach.level, reach.actuator};
      // The process models' extra inputs, so the file holds everything the reach's estimators
      // read (`canalid identify --online --config` takes them by name).
      for (const std::string* extra : {&reach.actuator_position, &reach.lpv_scheduling}) {
        if (!extra->empty() &&
            std::find(r->channels.begin(), r->channels.end(), *extra) == r->channels.end()) {
          r->channels.push_back(*extra);
        }
      }
      r->sample_time_s = config::ReachSampleTimeS(*config_.config(), reach);
      r->file = Open(reach.name + ".csv");
      std::fprintf(r->file, "time_s");
      for (const std::string& c : r->channels) std::fprintf(r->file, ",%s", c.c_str());
      std::fprintf(r->file, ",wall_time_s\n");
      file = r.get();
      reach_channels_[reach.name] = {reach.inflow, reach.outflow, reach.level, reach.actuator};
      reaches_.push_back(std::move(r));
    }
    if (file->indices.empty()) {
      for (const std::string& c : file->channels) {
        const int index = SampleChannelIndex(sample, c);
        if (index < 0) {
          throw InputError(MissingChannelMessage(log_path_, event.offset, c, reach.name, plc));
        }
        file->indices.push_back(index);
      }
    }
    if (file->last_sequence) {
      // Dropped polls leave a gap; a restarted daemon's sequence starts again: one sample on.
      const std::int64_t step =
          sample.sequence > *file->last_sequence ? sample.sequence - *file->last_sequence : 1;
      file->time_s += static_cast<double>(step) * file->sample_time_s;
    }
    file->last_sequence = sample.sequence;
    std::fprintf(file->file, "%.17g", file->time_s);
    for (const int i : file->indices) {
      const auto k = static_cast<std::size_t>(i);
      const bool valid = k < sample.quality.size() &&
                         sample.quality[k] == canalid::sample_t::QUALITY_VALID &&
                         std::isfinite(sample.values[k]);
      Cell(file->file, valid ? sample.values[k] : kNan);
    }
    Cell(file->file, static_cast<double>(sample.utime) * 1e-6);
    std::fputc('\n', file->file);
    ++rows_[reach.name + ".csv"];
  }
}

void LogExporter::OnModel(const canalid::model_snapshot_t& model,
                          const drivers::LogEvent& /*event*/) {
  if (!reach_filter_.empty() && model.reach != reach_filter_) return;
  if (models_ == nullptr) {
    models_ = Open("models.csv");
    std::fprintf(models_, "wall_time_s,reach,model_kind,estimator,samples_used");
    for (const std::string& p : model_parameters_)
      std::fprintf(models_, ",%s,%s_std", p.c_str(), p.c_str());
    std::fprintf(models_, ",trace_p,condition_number,excitation,prediction_error_rms,flags\n");
  }
  std::fprintf(models_, "%.17g,%s,%s,%s,%lld", static_cast<double>(model.utime) * 1e-6,
               model.reach.c_str(), model.model_kind.c_str(), model.estimator.c_str(),
               static_cast<long long>(model.samples_used));
  for (const std::string& p : model_parameters_) {
    double value = kNan, std = kNan;
    for (std::size_t i = 0; i < model.param_names.size(); ++i) {
      if (model.param_names[i] == p) {
        value = model.param_values[i];
        std = model.param_std_devs[i];
      }
    }
    Cell(models_, value);
    Cell(models_, std);
  }
  Cell(models_, model.trace_p);
  Cell(models_, model.condition_number);
  Cell(models_, model.excitation);
  Cell(models_, model.prediction_error_rms);
  std::fprintf(models_, ",%d\n", model.flags);
  ++rows_["models.csv"];
}

void LogExporter::Finish() {
  bool failed = false;
  for (std::FILE* f : files_) failed = std::fclose(f) != 0 || failed;
  files_.clear();
  models_ = nullptr;
  if (failed) throw InputError("--out " + dir_ + ": a file could not be written completely");
}

void ModelParameterCollector::OnModel(const canalid::model_snapshot_t& model,
                                      const drivers::LogEvent& /*event*/) {
  for (const std::string& name : model.param_names) {
    if (seen_.insert(name).second) names.push_back(name);
  }
}

}  // namespace canalid::cli
