#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "daemon/dashboard/dashboard_store.h"

namespace canalid::dashboard {

/// `message` as compact text; names come from the bus, so bytes that are not UTF-8 are replaced
/// (never an exception).
std::string DumpJson(const nlohmann::json& message);

/// The latest state of every site (no point history): layouts, sources with their channels'
/// last values, reaches with their experiment and every estimator's latest model, health.
/// Series are named by id; ages are seconds before `now_utime` (us since the epoch).
/// The format is documented in docs/dashboard.md.
nlohmann::json StateJson(const DashboardStore& store, std::int64_t now_utime);

/// The points of one series as [[t, value, sd], ...] (sd null when none), from sequence number
/// `from` on, at most `max_points` of them (evenly thinned, the newest always kept).
nlohmann::json PointsJson(const Series& series, std::int64_t from, std::size_t max_points);

/// Points in a snapshot at most, over every series (about 11 MB of JSON): with many series each
/// gets fewer than max_points_per_series.
inline constexpr std::size_t kSnapshotPointBudget = 250000;

/// {"type": "snapshot", "now": s, "state": StateJson, "points": {id: PointsJson}}: what a page
/// loads first; each series thinned to max_points_per_series (fewer when the budget asks it).
std::string SnapshotJson(const DashboardStore& store, std::int64_t now_utime,
                         std::size_t max_points_per_series);

/// The points appended since the last Next(), with the whole latest state: what a page is sent
/// a few times a second.
class DeltaWriter {
 public:
  /// {"type": "delta", "now": s, "state": StateJson, "points": {id: new points}}, each series'
  /// new points thinned to at most max_points_per_series (a burst, a log played fast).
  std::string Next(const DashboardStore& store, std::int64_t now_utime,
                   std::size_t max_points_per_series);

 private:
  std::map<int, std::int64_t> sent_;  ///< series id -> the next sequence number to send
};

}  // namespace canalid::dashboard
