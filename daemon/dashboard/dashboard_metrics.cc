#include "daemon/dashboard/dashboard_metrics.h"

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <utility>
#include <vector>

namespace canalid::dashboard {
namespace {

using Labels = std::initializer_list<std::pair<const char*, std::string_view>>;

// The length of the well-formed UTF-8 sequence starting at `s[i]`, 0 when it is not one.
std::size_t Utf8Length(std::string_view s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t n = 0;
  unsigned char low = 0x80, high = 0xBF;  // the second byte's range (RFC 3629 table)
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) low = 0xA0;
    if (c == 0xED) high = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) low = 0x90;
    if (c == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + n > s.size() || byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return n;
}

// A label value escaped as the text format asks (backslash, double quote and newline), and
// made UTF-8: names come from the bus, and one invalid byte would make a scraper reject the
// whole page, so such bytes become U+FFFD.
std::string Escaped(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size();) {
    const std::size_t n = Utf8Length(value, i);
    if (n == 0) {
      out += "\xEF\xBF\xBD";
      ++i;
      continue;
    }
    if (n > 1) {
      out.append(value.substr(i, n));
      i += n;
      continue;
    }
    const char c = value[i++];
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string Value(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// The samples of one metric family, written together under its HELP and TYPE lines.
class Family {
 public:
  Family(const char* name, const char* type, const char* help)
      : name_(name), type_(type), help_(help) {}
  void Add(Labels labels, double value) {
    samples_ += name_;
    if (labels.size() > 0) {
      samples_ += '{';
      bool first = true;
      for (const auto& [key, text] : labels) {
        if (!first) samples_ += ',';
        first = false;
        samples_ += key;
        samples_ += "=\"";
        samples_ += Escaped(text);
        samples_ += '"';
      }
      samples_ += '}';
    }
    samples_ += ' ';
    samples_ += Value(value);
    samples_ += '\n';
  }
  void WriteTo(std::string& out) const {
    if (samples_.empty()) return;
    out += "# HELP " + name_ + " " + help_ + "\n# TYPE " + name_ + " " + type_ + "\n";
    out += samples_;
  }

 private:
  std::string name_, type_, help_, samples_;
};

}  // namespace

std::string MetricsText(const DashboardStore& store, const drivers::HttpServerStats& server,
                        std::int64_t now_utime) {
  Family health_counter("canalid_health_counter_total", "counter",
                        "A counter of a daemon component, from its HEALTH message.");
  Family health_gauge("canalid_health_gauge", "gauge",
                      "A gauge of a daemon component, from its HEALTH message.");
  Family uptime("canalid_health_uptime_seconds", "gauge",
                "Time since the daemon started, from its latest HEALTH message.");
  Family channel_value("canalid_channel_value", "gauge",
                       "The last valid value of a PLC channel, its engineering unit.");
  Family channel_quality("canalid_channel_quality", "gauge",
                         "The quality of a channel's last reading (0 valid).");
  Family source_status("canalid_source_status", "gauge",
                       "The status of a PLC's last poll (0 ok, see docs/lcm-channels.md).");
  Family round_trip("canalid_source_round_trip_seconds", "gauge",
                    "Time the PLC's last poll spent reading.");
  Family source_age("canalid_source_age_seconds", "gauge", "Time since the PLC's last sample.");
  Family dropped("canalid_source_dropped_samples_total", "counter",
                 "Polls whose samples the dashboard never received (sequence gaps).");
  Family param("canalid_model_param", "gauge", "An estimator's latest parameter, SI units.");
  Family param_std("canalid_model_param_std", "gauge",
                   "The standard deviation of an estimator's latest parameter (1 sigma).");
  Family samples_used("canalid_model_samples_used", "gauge",
                      "Samples the estimator's latest model has seen.");
  Family flags("canalid_model_flags", "gauge", "The health flags of the latest model (FLAG_*).");
  Family prediction("canalid_model_prediction_error_rms", "gauge",
                    "RMS one-step prediction error over the last window.");
  Family model_age("canalid_model_age_seconds", "gauge", "Time since the latest model's data.");
  Family experiment_state("canalid_experiment_state", "gauge",
                          "The experiment state of a reach (STATE_*: 0 idle .. 6 aborted).");
  Family experiment_step("canalid_experiment_step", "gauge", "The current excitation step.");
  Family experiment_steps("canalid_experiment_steps", "gauge", "The planned excitation steps.");
  Family setpoint("canalid_experiment_setpoint", "gauge",
                  "The setpoint commanded to the excited channel.");
  Family messages("canalid_dashboard_messages_total", "counter",
                  "LCM messages the dashboard received, by what became of them.");
  Family http("canalid_dashboard_http_total", "counter", "HTTP and WebSocket events.");
  Family open("canalid_dashboard_connections", "gauge", "Open HTTP and WebSocket connections.");
  Family websockets("canalid_dashboard_websocket_clients", "gauge", "Live page connections.");
  Family queued("canalid_dashboard_websocket_queued_bytes", "gauge",
                "Bytes waiting to be sent to every page.");

  const auto age = [now_utime](std::int64_t utime) {  // in doubles: bus times may be anything
    return (static_cast<double>(now_utime) - static_cast<double>(utime)) * 1e-6;
  };
  for (const auto& [prefix, site] : store.sites()) {
    for (const auto& [component, h] : site.health) {
      for (std::size_t i = 0; i < h.counter_names.size(); ++i) {
        health_counter.Add(
            {{"site", prefix}, {"component", component}, {"name", h.counter_names[i]}},
            static_cast<double>(h.counter_values[i]));
      }
      for (std::size_t i = 0; i < h.gauge_names.size(); ++i) {
        health_gauge.Add({{"site", prefix}, {"component", component}, {"name", h.gauge_names[i]}},
                         h.gauge_values[i]);
      }
      uptime.Add({{"site", prefix}, {"component", component}}, h.uptime_s);
    }
    for (const auto& [name, source] : site.sources) {
      const Labels labels = {{"site", prefix}, {"source", name}};
      source_status.Add(labels, source.status);
      round_trip.Add(labels, source.round_trip_s);
      source_age.Add(labels, age(source.utime));
      dropped.Add(labels, static_cast<double>(source.dropped));
      for (const auto& [channel, state] : source.channels) {
        const Labels channel_labels = {{"site", prefix}, {"source", name}, {"channel", channel}};
        channel_value.Add(channel_labels, state.value);
        channel_quality.Add(channel_labels, state.quality);
      }
    }
    for (const auto& [reach, state] : site.reaches) {
      if (state.experiment) {
        const auto& e = *state.experiment;
        const Labels labels = {{"site", prefix}, {"reach", reach}, {"experiment", e.experiment}};
        experiment_state.Add(labels, e.state);
        experiment_step.Add(labels, e.step);
        experiment_steps.Add(labels, e.num_steps);
        setpoint.Add(labels, e.setpoint);
      }
      for (const auto& [key, track] : state.models) {
        const auto& m = track.latest;
        const Labels labels = {
            {"site", prefix}, {"reach", reach}, {"kind", m.model_kind}, {"estimator", m.estimator}};
        samples_used.Add(labels, static_cast<double>(m.samples_used));
        flags.Add(labels, m.flags);
        prediction.Add(labels, m.prediction_error_rms);
        model_age.Add(labels, age(m.utime));
        for (std::size_t i = 0; i < m.param_names.size(); ++i) {
          const Labels param_labels = {{"site", prefix},
                                       {"reach", reach},
                                       {"kind", m.model_kind},
                                       {"estimator", m.estimator},
                                       {"param", m.param_names[i]}};
          param.Add(param_labels, m.param_values[i]);
          param_std.Add(param_labels, m.param_std_devs[i]);
        }
      }
    }
  }
  const StoreCounters& c = store.counters();
  messages.Add({{"result", "used"}}, static_cast<double>(c.used));
  messages.Add({{"result", "malformed"}}, static_cast<double>(c.malformed));
  messages.Add({{"result", "ignored"}}, static_cast<double>(c.ignored));
  messages.Add({{"result", "refused"}}, static_cast<double>(c.refused));
  Family series_refused("canalid_dashboard_series_refused_total", "counter",
                        "Series whose history was not kept: over the series limit.");
  series_refused.Add({}, static_cast<double>(c.series_refused));
  const std::vector<std::pair<const char*, std::int64_t>> events = {
      {"connections_accepted", server.connections_accepted},
      {"connections_refused", server.connections_refused},
      {"requests", server.requests},
      {"bad_requests", server.bad_requests},
      {"handler_failures", server.handler_failures},
      {"websocket_opened", server.websocket_opened},
      {"websocket_dropped_slow", server.websocket_dropped_slow}};
  for (const auto& [event, count] : events) {
    http.Add({{"event", event}}, static_cast<double>(count));
  }
  open.Add({}, server.open_connections);
  websockets.Add({}, server.websocket_clients);
  queued.Add({}, static_cast<double>(server.websocket_queued_bytes));

  std::string out;
  for (const Family* family : {&health_counter,
                               &health_gauge,
                               &uptime,
                               &channel_value,
                               &channel_quality,
                               &source_status,
                               &round_trip,
                               &source_age,
                               &dropped,
                               &param,
                               &param_std,
                               &samples_used,
                               &flags,
                               &prediction,
                               &model_age,
                               &experiment_state,
                               &experiment_step,
                               &experiment_steps,
                               &setpoint,
                               &messages,
                               &series_refused,
                               &http,
                               &open,
                               &websockets,
                               &queued}) {
    family->WriteTo(out);
  }
  return out;
}

}  // namespace canalid::dashboard
