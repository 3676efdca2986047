#include "daemon/dashboard/dashboard_app.h"

#include <charconv>
#include <chrono>
#include <stdexcept>

#include "daemon/config/config_loader.h"
#include "daemon/dashboard/dashboard_assets.h"
#include "daemon/dashboard/dashboard_metrics.h"

namespace canalid::dashboard {
namespace {

constexpr const char* kJson = "application/json";

drivers::HttpResponse JsonResponse(int status, const nlohmann::json& body) {
  return {status, kJson, DumpJson(body), "no-store"};
}

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

}  // namespace

DashboardApp::DashboardApp(boost::asio::io_context& io, DashboardOptions options)
    : io_(io),
      options_(std::move(options)),
      store_(options_.limits),
      server_(
          io, options_.http, [this](std::string_view target) { return Get(target); },
          [this] {
            return std::make_shared<const std::string>(
                SnapshotJson(store_, NowUtime(), options_.snapshot_points));
          }),
      tick_(io) {
  if (!options_.log) options_.log = [](const std::string&) {};
  for (const std::string& path : options_.config_paths) {
    const std::string prefix = store_.SetLayout(daemon::LoadDaemonConfig(path), path);
    std::string text = "layout of site " + prefix;
    text += " from " + path;
    options_.log(text);
  }
  if (!options_.log_path.empty()) {
    playback_ = std::make_unique<LogPlayback>(
        io_, options_.log_path, options_.speed,
        [this](std::string_view channel, std::span<const std::uint8_t> data, std::int64_t) {
          OnLogMessage(channel, data);
        },
        [this](std::int64_t events, const std::string& how) {
          std::string text = "log " + options_.log_path;
          text += " played: " + std::to_string(events) + " events, end: ";
          text += how;
          options_.log(text);
        });
  } else {
    bus_ = std::make_unique<drivers::LcmBus>(options_.lcm_url);
    bus_->Subscribe(
        ".*",
        [this](const std::string& channel, std::span<const std::uint8_t> data) {
          return store_.OnMessage(channel, data) != Ingest::kMalformed;
        },
        10000);
    bus_watch_ = std::make_unique<drivers::BusWatch>(
        io_, *bus_, [] {}, [this] { return stopping_; },
        [this](bool, const std::string& text) { options_.log(text); });
  }
}

DashboardApp::~DashboardApp() {
  try {
    Stop();
  } catch (...) {  // closing sockets does not throw; nothing may escape a destructor
  }
}

void DashboardApp::OnLogMessage(std::string_view channel, std::span<const std::uint8_t> data) {
  store_.OnMessage(channel, data);
}

int DashboardApp::Start() {
  const int port = server_.Listen(options_.host, options_.port);
  if (playback_) playback_->Start();
  if (bus_watch_) bus_watch_->Start();
  Tick();
  return port;
}

void DashboardApp::Stop() {
  if (stopping_) return;
  stopping_ = true;
  tick_.cancel();
  if (playback_) playback_->Cancel();
  if (bus_watch_) bus_watch_->Cancel();
  server_.Stop();
}

std::int64_t DashboardApp::NowUtime() const {
  // A played log's ages are against its own clock (its newest message), not today's.
  if (playback_) return store_.newest_utime();
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void DashboardApp::Tick() {
  if (stopping_) return;
  // The writer advances even with nobody connected, so a page that connects later is not sent
  // the whole history twice (its snapshot has it).
  server_.Broadcast(std::make_shared<const std::string>(
      deltas_.Next(store_, NowUtime(), options_.snapshot_points)));
  tick_.expires_after(Seconds(options_.update_period_s));
  tick_.async_wait([this](const boost::system::error_code& error) {
    if (!error) Tick();
  });
}

drivers::HttpResponse DashboardApp::Get(std::string_view target) {
  const std::size_t query_at = target.find('?');
  const std::string_view path = target.substr(0, query_at);
  if (path == "/" || path == "/index.html") {
    const Asset* page = FindAsset("/index.html");
    return {200, std::string(page->content_type), std::string(page->body), "no-cache"};
  }
  if (const Asset* asset = FindAsset(path)) {
    return {200, std::string(asset->content_type), std::string(asset->body), "max-age=3600"};
  }
  const std::int64_t now = NowUtime();
  if (path == "/metrics") {
    return {200, "text/plain; version=0.0.4; charset=utf-8",
            MetricsText(store_, server_.stats(), now), "no-store"};
  }
  if (path == "/api" || path == "/api/") {
    return JsonResponse(
        200, {{"endpoints",
               {{"/api/state", "the latest state of every site (no history)"},
                {"/api/snapshot", "the state and every series, thinned to at most " +
                                      std::to_string(options_.snapshot_points) + " points"},
                {"/api/series/ID", "every point kept of one series: [[t, value, sd], ...]"},
                {"/metrics", "Prometheus text format"},
                {"/ws", "WebSocket: a snapshot, then deltas every " +
                            std::to_string(options_.update_period_s) + " s"}}}});
  }
  if (path == "/api/state") return JsonResponse(200, StateJson(store_, now));
  if (path == "/api/snapshot") {
    return {200, kJson, SnapshotJson(store_, now, options_.snapshot_points), "no-store"};
  }
  constexpr std::string_view kSeries = "/api/series/";
  if (path.substr(0, kSeries.size()) == kSeries) {
    const std::string_view text = path.substr(kSeries.size());
    int id = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), id);
    const auto it = store_.series().find(id);
    if (error != std::errc() || end != text.data() + text.size() || it == store_.series().end()) {
      return JsonResponse(404, {{"error", "no series '" + std::string(text) + "'"}});
    }
    return JsonResponse(
        200, {{"id", id},
              {"points",
               PointsJson(*it->second, 0, static_cast<std::size_t>(it->second->ring.appended()))}});
  }
  return {404, "text/plain; charset=utf-8", "not found: " + std::string(path) + "\n", "no-store"};
}

}  // namespace canalid::dashboard
