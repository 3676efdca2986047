#include "daemon/dashboard/dashboard_json.h"

#include <algorithm>
#include <cmath>

namespace canalid::dashboard {
namespace {

using nlohmann::json;

// In doubles: times come from the bus, and their difference may not fit an int64.
double AgeS(std::int64_t utime, std::int64_t now_utime) {
  return (static_cast<double>(now_utime) - static_cast<double>(utime)) * 1e-6;
}

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json LayoutJson(const SiteLayout& layout) {
  json reaches = json::array();
  for (const ReachLayout& r : layout.reaches) {
    reaches.push_back({{"name", r.name},
                       {"level", r.level},
                       {"inflow", r.inflow},
                       {"outflow", r.outflow},
                       {"actuator", r.actuator},
                       {"actuator_position", r.actuator_position},
                       {"level_min_m", r.level_min_m},
                       {"level_max_m", r.level_max_m}});
  }
  return {{"source", layout.source},
          {"version", layout.version},
          {"reaches", reaches},
          {"channel_units", layout.channel_units}};
}

json SourceJson(const std::string& name, const SourceState& s, std::int64_t now_utime) {
  json channels = json::array();
  for (const auto& [channel, state] : s.channels) {
    channels.push_back({{"name", channel},
                        {"value", Number(state.value)},
                        {"quality", state.quality},
                        {"series", state.series != nullptr ? json(state.series->id) : json()}});
  }
  return {{"name", name},
          {"utime", s.utime},
          {"age_s", AgeS(s.utime, now_utime)},
          {"sequence", s.sequence},
          {"status", s.status},
          {"exception_code", s.exception_code},
          {"round_trip_s", Number(s.round_trip_s)},
          {"samples", s.samples},
          {"dropped", s.dropped},
          {"channels", channels}};
}

json ModelJson(const ModelTrack& track, std::int64_t now_utime) {
  const canalid::model_snapshot_t& m = track.latest;
  json params = json::array();
  for (std::size_t i = 0; i < m.param_names.size(); ++i) {
    const auto it = track.params.find(m.param_names[i]);
    const Series* series = it == track.params.end() ? nullptr : it->second;
    params.push_back({{"name", m.param_names[i]},
                      {"value", Number(m.param_values[i])},
                      {"std", Number(m.param_std_devs[i])},
                      {"series", series != nullptr ? json(series->id) : json()}});
  }
  return {{"kind", m.model_kind},
          {"estimator", m.estimator},
          {"utime", m.utime},
          {"age_s", AgeS(m.utime, now_utime)},
          {"samples_used", m.samples_used},
          {"prediction_error_rms", Number(m.prediction_error_rms)},
          {"trace_p", Number(m.trace_p)},
          {"condition_number", Number(m.condition_number)},
          {"excitation", Number(m.excitation)},
          {"flags", m.flags},
          {"params", params}};
}

const char* StateName(int state) {
  switch (state) {
    case canalid::experiment_state_t::STATE_IDLE:
      return "idle";
    case canalid::experiment_state_t::STATE_ARMED:
      return "armed";
    case canalid::experiment_state_t::STATE_SETTLING:
      return "settling";
    case canalid::experiment_state_t::STATE_EXCITING:
      return "exciting";
    case canalid::experiment_state_t::STATE_RECOVERING:
      return "recovering";
    case canalid::experiment_state_t::STATE_DONE:
      return "done";
    case canalid::experiment_state_t::STATE_ABORTED:
      return "aborted";
    default:
      return "unknown";
  }
}

json ReachJson(const std::string& name, const ReachState& r, std::int64_t now_utime) {
  json experiment;
  if (r.experiment) {
    const auto& e = *r.experiment;
    experiment = {{"experiment", e.experiment},
                  {"state", StateName(e.state)},
                  {"state_code", e.state},
                  {"step", e.step},
                  {"num_steps", e.num_steps},
                  {"setpoint_channel", e.setpoint_channel},
                  {"setpoint", Number(e.setpoint)},
                  {"reason", e.reason},
                  {"utime", e.utime},
                  {"age_s", AgeS(e.utime, now_utime)}};
  }
  json models = json::array();
  for (const auto& [key, track] : r.models) models.push_back(ModelJson(track, now_utime));
  return {{"name", name}, {"experiment", experiment}, {"models", models}};
}

json HealthJson(const canalid::health_t& h, std::int64_t now_utime) {
  json counters = json::object();
  for (std::size_t i = 0; i < h.counter_names.size(); ++i) {
    counters[h.counter_names[i]] = h.counter_values[i];
  }
  json gauges = json::object();
  for (std::size_t i = 0; i < h.gauge_names.size(); ++i) {
    gauges[h.gauge_names[i]] = Number(h.gauge_values[i]);
  }
  return {
      {"component", h.component},       {"utime", h.utime},     {"age_s", AgeS(h.utime, now_utime)},
      {"uptime_s", Number(h.uptime_s)}, {"counters", counters}, {"gauges", gauges}};
}

}  // namespace

std::string DumpJson(const json& message) {
  return message.dump(-1, ' ', false, json::error_handler_t::replace);
}

json StateJson(const DashboardStore& store, std::int64_t now_utime) {
  json sites = json::array();
  for (const auto& [prefix, site] : store.sites()) {
    json sources = json::array();
    for (const auto& [name, source] : site.sources) {
      sources.push_back(SourceJson(name, source, now_utime));
    }
    json reaches = json::array();
    for (const auto& [name, reach] : site.reaches) {
      reaches.push_back(ReachJson(name, reach, now_utime));
    }
    json health = json::array();
    for (const auto& [component, h] : site.health) health.push_back(HealthJson(h, now_utime));
    sites.push_back(
        {{"prefix", prefix},
         {"layout", site.layout ? LayoutJson(*site.layout) : json()},
         {"layout_problem", site.layout_problem},
         {"last_utime", site.last_utime},
         {"age_s", site.last_utime > 0 ? Number(AgeS(site.last_utime, now_utime)) : json()},
         {"messages", site.messages},
         {"malformed", site.malformed},
         {"sources", sources},
         {"reaches", reaches},
         {"health", health}});
  }
  const StoreCounters& c = store.counters();
  return {{"sites", sites},
          {"messages",
           {{"used", c.used},
            {"malformed", c.malformed},
            {"ignored", c.ignored},
            {"refused", c.refused},
            {"series_refused", c.series_refused}}}};
}

json PointsJson(const Series& series, std::int64_t from, std::size_t max_points) {
  const SeriesRing& ring = series.ring;
  const std::int64_t first = std::max(from, ring.first_sequence());
  const std::int64_t count = ring.appended() - first;
  json points = json::array();
  if (count <= 0 || max_points == 0) return points;
  const auto n = static_cast<std::size_t>(count);
  const std::size_t stride = (n + max_points - 1) / max_points;
  const auto start = static_cast<std::size_t>(first - ring.first_sequence());
  // Thinned from the newest backwards, so the newest point is always sent.
  std::vector<std::size_t> picked;
  for (std::size_t k = n; k > 0; k = k > stride ? k - stride : 0) picked.push_back(start + k - 1);
  for (auto it = picked.rbegin(); it != picked.rend(); ++it) {
    const SeriesPoint& p = ring.at(*it);
    points.push_back({p.t, Number(p.value), Number(p.sd)});
  }
  return points;
}

std::string SnapshotJson(const DashboardStore& store, std::int64_t now_utime,
                         std::size_t max_points_per_series) {
  json points = json::object();
  const std::size_t count = std::max<std::size_t>(store.series().size(), 1);
  const std::size_t each =
      std::min(max_points_per_series, std::max<std::size_t>(10, kSnapshotPointBudget / count));
  for (const auto& [id, series] : store.series()) {
    points[std::to_string(id)] = PointsJson(*series, 0, each);
  }
  const json message = {{"type", "snapshot"},
                        {"now", static_cast<double>(now_utime) * 1e-6},
                        {"state", StateJson(store, now_utime)},
                        {"points", points}};
  return DumpJson(message);
}

std::string DeltaWriter::Next(const DashboardStore& store, std::int64_t now_utime,
                              std::size_t max_points_per_series) {
  json points = json::object();
  for (const auto& [id, series] : store.series()) {
    std::int64_t& next = sent_[id];
    if (series->ring.appended() > next) {
      points[std::to_string(id)] = PointsJson(*series, next, max_points_per_series);
      next = series->ring.appended();
    }
  }
  const json message = {{"type", "delta"},
                        {"now", static_cast<double>(now_utime) * 1e-6},
                        {"state", StateJson(store, now_utime)},
                        {"points", points}};
  return DumpJson(message);
}

}  // namespace canalid::dashboard
