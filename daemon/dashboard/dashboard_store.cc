#include "daemon/dashboard/dashboard_store.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include <canalid/config_t.hpp>
#include <canalid/sample_t.hpp>

#include "daemon/config/config_loader.h"
#include "drivers/lcm/bus.h"

namespace canalid::dashboard {
namespace {

enum class Topic { kNone, kSample, kModel, kExperiment, kHealth, kConfig };

struct Route {
  Topic topic = Topic::kNone;
  std::string prefix;
  std::string suffix;  ///< the PLC of a SAMPLE_ channel
};

// The channel's prefix and topic: the earliest of the keywords `SAMPLE_`, `MODEL_`,
// `EXPERIMENT_` (followed by a name), or `HEALTH` / `CONFIG` ending the channel.
Route RouteOf(std::string_view channel) {
  struct Keyword {
    std::string_view text;
    Topic topic;
    bool at_end;
  };
  constexpr std::array<Keyword, 5> kKeywords = {{{"SAMPLE_", Topic::kSample, false},
                                                 {"MODEL_", Topic::kModel, false},
                                                 {"EXPERIMENT_", Topic::kExperiment, false},
                                                 {"HEALTH", Topic::kHealth, true},
                                                 {"CONFIG", Topic::kConfig, true}}};
  Route best;
  std::size_t best_at = std::string_view::npos;
  for (const Keyword& k : kKeywords) {
    std::size_t at = std::string_view::npos;
    if (k.at_end) {
      if (channel.size() >= k.text.size() &&
          channel.substr(channel.size() - k.text.size()) == k.text) {
        at = channel.size() - k.text.size();
      }
    } else {
      at = channel.find(k.text);
      if (at != std::string_view::npos && at + k.text.size() == channel.size()) {
        at = std::string_view::npos;  // no name after the keyword
      }
    }
    if (at < best_at) {
      best_at = at;
      best.topic = k.topic;
      best.prefix = std::string(channel.substr(0, at));
      best.suffix = std::string(channel.substr(at + k.text.size()));
    }
  }
  return best;
}

SiteLayout LayoutOf(const config::DaemonConfig& config, const std::string& source) {
  SiteLayout layout;
  layout.source = source;
  for (const auto& channel : config.channels) layout.channel_units[channel.name] = channel.unit;
  for (const auto& r : config.reaches) {
    layout.reaches.push_back({r.name, r.level, r.inflow, r.outflow, r.actuator, r.actuator_position,
                              r.level_min_m, r.level_max_m});
  }
  return layout;
}

}  // namespace

DashboardStore::DashboardStore(StoreLimits limits) : limits_(limits) {}

SiteState* DashboardStore::Site(const std::string& prefix) {
  if (auto it = sites_.find(prefix); it != sites_.end()) return &it->second;
  if (sites_.size() >= limits_.max_sites) return nullptr;
  SiteState& site = sites_[prefix];
  site.prefix = prefix;
  return &site;
}

Series* DashboardStore::NewSeries() {
  if (series_.size() >= limits_.max_series) {
    ++counters_.series_refused;
    return nullptr;
  }
  const int id = next_series_id_++;
  auto series =
      std::make_unique<Series>(Series{id, SeriesRing(limits_.max_points, limits_.history_s)});
  Series* raw = series.get();
  series_.emplace(id, std::move(series));
  return raw;
}

Ingest DashboardStore::OnMessage(std::string_view channel, std::span<const std::uint8_t> data) {
  const Route route = RouteOf(channel);
  if (route.topic == Topic::kNone) {
    ++counters_.ignored;
    return Ingest::kIgnored;
  }
  SiteState* site = Site(route.prefix);
  if (site == nullptr) {
    ++counters_.refused;
    return Ingest::kRefused;
  }
  Ingest result = Ingest::kUsed;
  switch (route.topic) {
    case Topic::kSample:
      OnSample(*site, route.suffix, data, result);
      break;
    case Topic::kModel:
      OnModel(*site, data, result);
      break;
    case Topic::kExperiment:
      OnExperiment(*site, data, result);
      break;
    case Topic::kHealth:
      OnHealth(*site, data, result);
      break;
    case Topic::kConfig:
      OnConfig(*site, data, result);
      break;
    case Topic::kNone:
      break;
  }
  if (result == Ingest::kMalformed) {
    ++counters_.malformed;
    ++site->malformed;
  } else {
    ++counters_.used;
    ++site->messages;
  }
  return result;
}

void DashboardStore::OnSample(SiteState& site, const std::string& source,
                              std::span<const std::uint8_t> data, Ingest& result) {
  canalid::sample_t sample;
  if (!drivers::DecodeMessage(data, sample) || sample.num_channels < 0) {
    result = Ingest::kMalformed;
    return;
  }
  SourceState& state = site.sources[source];
  if (state.sequence >= 0 && sample.sequence > state.sequence + 1) {
    state.dropped += sample.sequence - state.sequence - 1;
  }
  state.utime = sample.utime;
  state.sequence = sample.sequence;
  state.status = sample.status;
  state.exception_code = sample.exception_code;
  state.round_trip_s = sample.round_trip_s;
  ++state.samples;
  const double t = static_cast<double>(sample.utime) * 1e-6;
  for (std::size_t i = 0; i < sample.channel_names.size(); ++i) {
    auto [it, added] = state.channels.try_emplace(sample.channel_names[i]);
    ChannelState& channel = it->second;
    if (added) channel.series = NewSeries();
    channel.quality = sample.quality[i];
    if (sample.quality[i] != canalid::sample_t::QUALITY_VALID) continue;
    channel.value = sample.values[i];
    if (channel.series != nullptr) {
      channel.series->ring.Append({t, static_cast<float>(sample.values[i]), NAN});
    }
  }
  site.last_utime = std::max(site.last_utime, sample.utime);
  newest_utime_ = std::max(newest_utime_, sample.utime);
}

void DashboardStore::OnModel(SiteState& site, std::span<const std::uint8_t> data, Ingest& result) {
  canalid::model_snapshot_t model;
  if (!drivers::DecodeMessage(data, model) || model.num_params < 0) {
    result = Ingest::kMalformed;
    return;
  }
  ModelTrack& track = site.reaches[model.reach].models[model.model_kind + "/" + model.estimator];
  const double t = static_cast<double>(model.utime) * 1e-6;
  for (std::size_t i = 0; i < model.param_names.size(); ++i) {
    auto [it, added] = track.params.try_emplace(model.param_names[i], nullptr);
    if (added) it->second = NewSeries();
    if (it->second != nullptr) {
      it->second->ring.Append({t, static_cast<float>(model.param_values[i]),
                               static_cast<float>(model.param_std_devs[i])});
    }
  }
  site.last_utime = std::max(site.last_utime, model.utime);
  newest_utime_ = std::max(newest_utime_, model.utime);
  track.latest = std::move(model);
}

void DashboardStore::OnExperiment(SiteState& site, std::span<const std::uint8_t> data,
                                  Ingest& result) {
  canalid::experiment_state_t state;
  if (!drivers::DecodeMessage(data, state)) {
    result = Ingest::kMalformed;
    return;
  }
  site.last_utime = std::max(site.last_utime, state.utime);
  newest_utime_ = std::max(newest_utime_, state.utime);
  site.reaches[state.reach].experiment = std::move(state);
}

void DashboardStore::OnHealth(SiteState& site, std::span<const std::uint8_t> data, Ingest& result) {
  canalid::health_t health;
  if (!drivers::DecodeMessage(data, health) || health.num_counters < 0 || health.num_gauges < 0) {
    result = Ingest::kMalformed;
    return;
  }
  site.last_utime = std::max(site.last_utime, health.utime);
  newest_utime_ = std::max(newest_utime_, health.utime);
  site.health[health.component] = std::move(health);
}

void DashboardStore::OnConfig(SiteState& site, std::span<const std::uint8_t> data, Ingest& result) {
  canalid::config_t config;
  if (!drivers::DecodeMessage(data, config)) {
    result = Ingest::kMalformed;
    return;
  }
  try {
    const config::DaemonConfig parsed = daemon::ParseDaemonConfig(config.text, "CONFIG message");
    site.layout = LayoutOf(parsed, "CONFIG message");
    site.layout->version = config.version;
    site.layout_problem.clear();
  } catch (const std::exception& e) {
    // The bytes are a config_t, but its text is no configuration this version reads: the
    // site keeps what it had, and the page says why.
    site.layout_problem = e.what();
  }
}

std::string DashboardStore::SetLayoutFromConfig(std::string_view text, const std::string& source) {
  const config::DaemonConfig parsed = daemon::ParseDaemonConfig(text, source);
  SiteState* site = Site(parsed.lcm.channel_prefix);
  if (site == nullptr) throw std::runtime_error(source + ": too many sites");
  site->layout = LayoutOf(parsed, source);
  return parsed.lcm.channel_prefix;
}

}  // namespace canalid::dashboard
