#pragma once
#include <cstdint>
#include <string>

#include "daemon/dashboard/dashboard_store.h"
#include "drivers/http/http_server.h"

namespace canalid::dashboard {

/// Everything the store knows, in the Prometheus text exposition format (version 0.0.4): each
/// daemon's health counters and gauges as in its HEALTH messages, the last value of every
/// channel, every estimator's latest parameters with their standard deviations, the experiments,
/// and the dashboard's own counters.  Labels name the site (channel prefix) and the rest; the
/// metric names are listed in docs/dashboard.md.
std::string MetricsText(const DashboardStore& store, const drivers::HttpServerStats& server,
                        std::int64_t now_utime);

}  // namespace canalid::dashboard
