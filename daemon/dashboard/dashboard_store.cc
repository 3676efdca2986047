#include "daemon/dashboard/dashboard_store.h"

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <stdexcept>
#include <variant>
#include <vector>

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

// The ways the channel can be read as `<prefix><KEYWORD>[name]`, in the order they are tried:
// after a known prefix (a site already seen; the longest first), then `HEALTH` / `CONFIG`
// ending the channel, then every `SAMPLE_`, `MODEL_`, `EXPERIMENT_` followed by a name, the
// earliest first.  A prefix may itself hold a keyword (MODEL_RIG_); the bytes decide: the first
// reading whose type they decode as is the one (the LCM type fingerprint rejects the others).
std::vector<Route> RoutesOf(std::string_view channel,
                            const std::map<std::string, SiteState>& known) {
  struct Keyword {
    std::string_view text;
    Topic topic;
    bool at_end;
  };
  constexpr std::array<Keyword, 5> kKeywords = {{{"HEALTH", Topic::kHealth, true},
                                                 {"CONFIG", Topic::kConfig, true},
                                                 {"SAMPLE_", Topic::kSample, false},
                                                 {"MODEL_", Topic::kModel, false},
                                                 {"EXPERIMENT_", Topic::kExperiment, false}}};
  // Readings with the keyword at `at` only.
  const auto readings_at = [&](std::size_t at, std::vector<Route>& out) {
    const std::string_view rest = channel.substr(at);
    for (const Keyword& k : kKeywords) {
      if (rest.substr(0, k.text.size()) != k.text) continue;
      const bool ends = rest.size() == k.text.size();
      if (k.at_end != ends) continue;  // HEALTH ends the channel; SAMPLE_ needs a name
      out.push_back(
          {k.topic, std::string(channel.substr(0, at)), std::string(rest.substr(k.text.size()))});
    }
  };
  std::vector<Route> routes;
  for (auto it = known.rbegin(); it != known.rend(); ++it) {  // the longest matching first
    const std::string& prefix = it->first;
    if (channel.substr(0, prefix.size()) == prefix) readings_at(prefix.size(), routes);
  }
  for (const Keyword& k : kKeywords) {
    if (k.at_end && channel.size() >= k.text.size()) {
      readings_at(channel.size() - k.text.size(), routes);
    }
  }
  for (std::size_t at = 0; at < channel.size(); ++at) {
    for (const Keyword& k : kKeywords) {
      if (!k.at_end && channel.substr(at, k.text.size()) == k.text &&
          at + k.text.size() < channel.size()) {
        routes.push_back({k.topic, std::string(channel.substr(0, at)),
                          std::string(channel.substr(at + k.text.size()))});
      }
    }
  }
  return routes;
}

using Decoded = std::variant<canalid::sample_t, canalid::model_snapshot_t,
                             canalid::experiment_state_t, canalid::health_t, canalid::config_t>;

template <class Message>
std::optional<Decoded> DecodeAs(std::span<const std::uint8_t> data) {
  Message message;
  if (!drivers::DecodeMessage(data, message)) return std::nullopt;
  return Decoded(std::move(message));
}

// The message as its channel's type, or nothing when the bytes are not one.
std::optional<Decoded> Decode(Topic topic, std::span<const std::uint8_t> data) {
  switch (topic) {
    case Topic::kSample:
      return DecodeAs<canalid::sample_t>(data);
    case Topic::kModel:
      return DecodeAs<canalid::model_snapshot_t>(data);
    case Topic::kExperiment:
      return DecodeAs<canalid::experiment_state_t>(data);
    case Topic::kHealth:
      return DecodeAs<canalid::health_t>(data);
    case Topic::kConfig:
      return DecodeAs<canalid::config_t>(data);
    case Topic::kNone:
      break;
  }
  return std::nullopt;
}

// A value as f32 for the history: beyond f32's range it is infinite (a cast would be undefined).
float ToFloat(double v) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (v > kMax) return std::numeric_limits<float>::infinity();
  if (v < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
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
  const std::vector<Route> routes = RoutesOf(channel, sites_);
  if (routes.empty()) {
    ++counters_.ignored;
    return Ingest::kIgnored;
  }
  // Decoded first: bytes that are not the channel's type make no site and change nothing.
  std::optional<Decoded> message;
  const Route* found = nullptr;
  for (const Route& candidate : routes) {
    message = Decode(candidate.topic, data);
    if (message) {
      found = &candidate;
      break;
    }
  }
  if (found == nullptr) {
    ++counters_.malformed;
    if (const auto it = sites_.find(routes.front().prefix); it != sites_.end()) {
      ++it->second.malformed;
    }
    return Ingest::kMalformed;
  }
  const Route& route = *found;
  SiteState* site = Site(route.prefix);
  Ingest result = site == nullptr ? Ingest::kRefused : Ingest::kUsed;
  if (site != nullptr) {
    if (auto* sample = std::get_if<canalid::sample_t>(&*message)) {
      result = OnSample(*site, route.suffix, *sample);
    } else if (auto* model = std::get_if<canalid::model_snapshot_t>(&*message)) {
      result = OnModel(*site, *model);
    } else if (auto* experiment = std::get_if<canalid::experiment_state_t>(&*message)) {
      result = OnExperiment(*site, *experiment);
    } else if (auto* health = std::get_if<canalid::health_t>(&*message)) {
      result = OnHealth(*site, *health);
    } else if (auto* config = std::get_if<canalid::config_t>(&*message)) {
      OnConfig(*site, *config);
    }
  }
  if (result == Ingest::kRefused) {
    ++counters_.refused;
  } else {
    ++counters_.used;
    ++site->messages;
  }
  return result;
}

Ingest DashboardStore::OnSample(SiteState& site, const std::string& source,
                                canalid::sample_t& sample) {
  SourceState* state = Entry(site.sources, source);
  if (state == nullptr) return Ingest::kRefused;
  // Forward gaps only: a restarted daemon counts from 0 again.
  if (state->sequence >= 0 && sample.sequence > state->sequence &&
      sample.sequence - state->sequence > 1) {
    state->dropped += sample.sequence - state->sequence - 1;
  }
  state->utime = sample.utime;
  state->sequence = sample.sequence;
  state->status = sample.status;
  state->exception_code = sample.exception_code;
  state->round_trip_s = sample.round_trip_s;
  ++state->samples;
  const double t = static_cast<double>(sample.utime) * 1e-6;
  for (std::size_t i = 0; i < sample.channel_names.size(); ++i) {
    const bool known = state->channels.count(sample.channel_names[i]) != 0;
    ChannelState* channel = Entry(state->channels, sample.channel_names[i]);
    if (channel == nullptr) continue;
    if (!known) channel->series = NewSeries();
    channel->quality = static_cast<unsigned char>(sample.quality[i]);  // 0..3 (QUALITY_*)
    if (sample.quality[i] != canalid::sample_t::QUALITY_VALID) continue;
    channel->value = sample.values[i];
    if (channel->series != nullptr) {
      channel->series->ring.Append({t, ToFloat(sample.values[i]), NAN});
    }
  }
  Saw(site, sample.utime);
  return Ingest::kUsed;
}

Ingest DashboardStore::OnModel(SiteState& site, canalid::model_snapshot_t& model) {
  ReachState* reach = Entry(site.reaches, model.reach);
  ModelTrack* track =
      reach == nullptr ? nullptr : Entry(reach->models, model.model_kind + "/" + model.estimator);
  if (track == nullptr) return Ingest::kRefused;
  const double t = static_cast<double>(model.utime) * 1e-6;
  for (std::size_t i = 0; i < model.param_names.size(); ++i) {
    const bool known = track->params.count(model.param_names[i]) != 0;
    Series** series = Entry(track->params, model.param_names[i]);
    if (series == nullptr) continue;
    if (!known) *series = NewSeries();
    if (*series != nullptr) {
      (*series)->ring.Append({t, ToFloat(model.param_values[i]), ToFloat(model.param_std_devs[i])});
    }
  }
  Saw(site, model.utime);
  track->latest = std::move(model);
  return Ingest::kUsed;
}

Ingest DashboardStore::OnExperiment(SiteState& site, canalid::experiment_state_t& state) {
  ReachState* reach = Entry(site.reaches, state.reach);
  if (reach == nullptr) return Ingest::kRefused;
  Saw(site, state.utime);
  reach->experiment = std::move(state);
  return Ingest::kUsed;
}

Ingest DashboardStore::OnHealth(SiteState& site, canalid::health_t& health) {
  canalid::health_t* slot = Entry(site.health, health.component);
  if (slot == nullptr) return Ingest::kRefused;
  Saw(site, health.utime);
  *slot = std::move(health);
  return Ingest::kUsed;
}

void DashboardStore::OnConfig(SiteState& site, const canalid::config_t& config) {
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

void DashboardStore::Saw(SiteState& site, std::int64_t utime) {
  site.last_utime = std::max(site.last_utime, utime);
  newest_utime_ = std::max(newest_utime_, utime);
}

std::string DashboardStore::SetLayout(const config::DaemonConfig& config,
                                      const std::string& source) {
  SiteState* site = Site(config.lcm.channel_prefix);
  if (site == nullptr) throw std::runtime_error(source + ": too many sites");
  site->layout = LayoutOf(config, source);
  return config.lcm.channel_prefix;
}

}  // namespace canalid::dashboard
