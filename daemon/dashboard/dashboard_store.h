#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <canalid/config_t.hpp>
#include <canalid/experiment_state_t.hpp>
#include <canalid/health_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>

#include "daemon/config/daemon_config.h"
#include "daemon/dashboard/series_ring.h"

namespace canalid::dashboard {

/// How much the dashboard keeps: memory is at most max_series x max_points x 16 bytes of points
/// (up to twice that while a ring grows) plus the latest message of each name, at most
/// max_sites x max_names of each kind.
struct StoreLimits {
  double history_s = 2.0 * 3600.0;  ///< points older than this before the newest are dropped
  std::size_t max_points = 7200;    ///< per series
  std::size_t max_series = 1024;    ///< in all; more are refused (counted)
  std::size_t max_sites = 32;       ///< channel prefixes; more are refused (counted)
  /// Names in each map of a site: sources, channels of a source, reaches, estimators of a reach,
  /// parameters of an estimator, health components.  More are refused (counted).
  std::size_t max_names = 256;
};

/// One series of points with the id the page and the API name it by.
struct Series {
  int id = 0;
  SeriesRing ring;
};

/// A reach as the daemon's configuration describes it (from the CONFIG message or --config).
struct ReachLayout {
  std::string name;
  std::string level, inflow, outflow, actuator, actuator_position;  ///< channel names
  double level_min_m = 0.0, level_max_m = 0.0;                      ///< the safety band
};

struct SiteLayout {
  std::string source;   ///< "CONFIG message" or the file it was read from
  std::string version;  ///< canalid version of the daemon ("" from a file)
  std::vector<ReachLayout> reaches;
  std::map<std::string, std::string> channel_units;  ///< channel -> unit
};

struct ChannelState {
  double value = 0.0;
  int quality = 0;
  Series* series = nullptr;  ///< null when the series limit refused it
};

/// A PLC poller's latest sample and its history.
struct SourceState {
  std::int64_t utime = 0;
  std::int64_t sequence = -1;
  int status = 0;
  int exception_code = 0;
  double round_trip_s = 0.0;
  std::int64_t samples = 0;
  std::int64_t dropped = 0;  ///< sequence numbers skipped: polls the dashboard never saw
  std::map<std::string, ChannelState> channels;
};

/// The latest snapshot of one estimator of a reach, and its parameters' history.
struct ModelTrack {
  canalid::model_snapshot_t latest;
  std::map<std::string, Series*> params;  ///< parameter name -> series (null: refused)
};

struct ReachState {
  std::optional<canalid::experiment_state_t> experiment;
  std::map<std::string, ModelTrack> models;  ///< "kind/estimator" -> track
};

/// Everything known of one daemon (one channel prefix).
struct SiteState {
  std::string prefix;
  std::optional<SiteLayout> layout;
  std::string layout_problem;  ///< why the last CONFIG did not parse
  std::int64_t last_utime = 0;
  std::int64_t messages = 0;
  std::int64_t malformed = 0;
  std::map<std::string, SourceState> sources;
  std::map<std::string, ReachState> reaches;
  std::map<std::string, canalid::health_t> health;  ///< component -> latest
};

/// What became of one message.
enum class Ingest { kUsed, kMalformed, kIgnored, kRefused };

struct StoreCounters {
  std::int64_t used = 0;
  std::int64_t malformed = 0;  ///< a canalid channel whose bytes do not decode as its type
  std::int64_t ignored = 0;    ///< not a channel the dashboard shows (commands, heartbeats, ...)
  std::int64_t refused = 0;    ///< over max_sites or max_names
  std::int64_t series_refused = 0;  ///< history not kept: over max_series
};

/// The dashboard's picture of every canalidd on the bus, built from their LCM messages
/// (`<prefix>SAMPLE_<plc>`, `MODEL_<reach>`, `EXPERIMENT_<reach>`, `HEALTH`, `CONFIG`; any
/// prefix, so several daemons on one bus are several sites).  A message that does not decode
/// is counted and changes nothing.  Single-threaded.
class DashboardStore {
 public:
  explicit DashboardStore(StoreLimits limits = {});

  Ingest OnMessage(std::string_view channel, std::span<const std::uint8_t> data);

  /// Sets the layout of the site a daemon configuration names ([lcm] channel_prefix; `source`
  /// says where it came from, e.g. the file given to --config) and returns that prefix.
  /// @throws std::runtime_error when the site would be one too many.
  std::string SetLayout(const config::DaemonConfig& config, const std::string& source);

  const std::map<std::string, SiteState>& sites() const { return sites_; }
  const StoreCounters& counters() const { return counters_; }
  const StoreLimits& limits() const { return limits_; }
  /// Every series, by id.
  const std::map<int, std::unique_ptr<Series>>& series() const { return series_; }
  /// The newest message time seen (us since the epoch), for ages in a replayed log.
  std::int64_t newest_utime() const { return newest_utime_; }

 private:
  SiteState* Site(const std::string& prefix);
  Series* NewSeries();
  Ingest OnSample(SiteState& site, const std::string& source, canalid::sample_t& sample);
  Ingest OnModel(SiteState& site, canalid::model_snapshot_t& model);
  Ingest OnExperiment(SiteState& site, canalid::experiment_state_t& state);
  Ingest OnHealth(SiteState& site, canalid::health_t& health);
  void OnConfig(SiteState& site, const canalid::config_t& config);
  void Saw(SiteState& site, std::int64_t utime);
  /// The entry `key` of `map`, made when absent and the map holds fewer than max_names; null
  /// (the message refused) otherwise.
  template <class Map>
  typename Map::mapped_type* Entry(Map& map, const std::string& key) {
    if (const auto it = map.find(key); it != map.end()) return &it->second;
    if (map.size() >= limits_.max_names) return nullptr;
    return &map[key];
  }

  StoreLimits limits_;
  StoreCounters counters_;
  std::map<std::string, SiteState> sites_;
  std::map<int, std::unique_ptr<Series>> series_;
  int next_series_id_ = 1;
  std::int64_t newest_utime_ = 0;
};

}  // namespace canalid::dashboard
