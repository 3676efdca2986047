#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

#include "daemon/config/config_loader.h"

namespace canalid::daemon {
namespace {

// Shortest decimal that reads back to the same double (std::to_chars), always a TOML float.
std::string Float(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  std::string text(buffer.data(), result.ptr);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

std::string String(const std::string& value) {
  std::string out = "\"";
  for (char c : value) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      std::array<char, 8> escape{};
      std::snprintf(escape.data(), escape.size(), "\\u%04x", u);
      out += escape.data();
    } else {
      out += c;
    }
  }
  return out + "\"";
}

class Writer {
 public:
  void Line(const std::string& text) { out_ += text + "\n"; }
  void Key(const char* key, const std::string& value) { Line(std::string(key) + " = " + value); }
  void Key(const char* key, double value) { Key(key, Float(value)); }
  void Key(const char* key, const char* value) { Key(key, String(value)); }
  void Str(const char* key, const std::string& value) { Key(key, String(value)); }
  void Int(const char* key, long long value) { Key(key, std::to_string(value)); }
  void Bool(const char* key, bool value) { Key(key, std::string(value ? "true" : "false")); }
  template <class E>
  void List(const char* key, const std::vector<E>& values) {
    Array(key, values, [](const E& value) { return String(config::EnumName(value)); });
  }
  void Strings(const char* key, const std::vector<std::string>& values) {
    Array(key, values, [](const std::string& value) { return String(value); });
  }
  void Numbers(const char* key, const std::vector<double>& values) {
    Array(key, values, [](double value) { return Float(value); });
  }
  std::string Take() { return std::move(out_); }

 private:
  // `key = [a, b, ...]`, each element written by `item`.
  template <class T, class Item>
  void Array(const char* key, const std::vector<T>& values, Item item) {
    std::string text = "[";
    for (std::size_t i = 0; i < values.size(); ++i) text += (i == 0 ? "" : ", ") + item(values[i]);
    Key(key, text + "]");
  }

  std::string out_;
};

}  // namespace

std::string RenderDaemonConfig(const config::DaemonConfig& c) {
  Writer w;
  w.Line("# canalidd effective configuration (every key, defaults filled in)");
  w.Line("[daemon]");
  w.Str("state_directory", c.daemon.state_directory);
  w.Key("log_level", config::EnumName(c.daemon.log_level));
  w.Key("time_scale", c.daemon.time_scale);
  if (c.daemon.heartbeat) {
    w.Line("[daemon.heartbeat]");
    w.Str("channel", c.daemon.heartbeat->channel);
    w.Key("period_s", c.daemon.heartbeat->period_s);
  }
  w.Line("");
  w.Line("[lcm]");
  w.Str("url", c.lcm.url);
  w.Str("channel_prefix", c.lcm.channel_prefix);
  w.Line("");
  w.Line("[results]");
  w.Str("listen", c.results.listen);
  w.Int("max_clients", c.results.max_clients);
  for (const config::PlcConfig& p : c.plcs) {
    w.Line("");
    w.Line("[[plc]]");
    w.Str("name", p.name);
    w.Key("transport", config::EnumName(p.transport));
    if (p.transport == config::PlcTransport::kTcp) {
      w.Str("host", p.host);
      w.Int("port", p.port);
      w.Key("connect_timeout_s", p.connect_timeout_s);
    } else {
      w.Str("device", p.device);
      w.Int("baud", p.baud);
      w.Str("parity", std::string(1, p.parity));
      w.Int("data_bits", p.data_bits);
      w.Int("stop_bits", p.stop_bits);
    }
    w.Int("unit_id", p.unit_id);
    w.Key("response_timeout_s", p.response_timeout_s);
    w.Key("poll_period_s", p.poll_period_s);
    w.Key("backoff_initial_s", p.backoff_initial_s);
    w.Key("backoff_max_s", p.backoff_max_s);
    w.Int("max_gap_registers", p.max_gap_registers);
    w.Int("timeouts_before_reconnect", p.timeouts_before_reconnect);
  }
  for (const config::ChannelConfig& ch : c.channels) {
    w.Line("");
    w.Line("[[channel]]");
    w.Str("name", ch.name);
    w.Str("plc", ch.plc);
    w.Key("role", config::EnumName(ch.role));
    w.Key("register", config::EnumName(ch.table));
    w.Int("address", ch.address);
    w.Key("type", config::EnumName(ch.type));
    w.Key("word_order", config::EnumName(ch.word_order));
    w.Key("scale", ch.scale);
    w.Key("offset", ch.offset);
    w.Str("unit", ch.unit);
    w.Key("valid_min", ch.valid_min);
    w.Key("valid_max", ch.valid_max);
    w.Bool("writable", ch.writable);
    if (ch.writable) {
      w.Key("setpoint_min", ch.setpoint_min);
      w.Key("setpoint_max", ch.setpoint_max);
      w.Key("max_rate_per_s", ch.max_rate_per_s);
    }
  }
  for (const config::ReachConfig& r : c.reaches) {
    w.Line("");
    w.Line("[[reach]]");
    w.Str("name", r.name);
    w.Str("inflow", r.inflow);
    w.Str("outflow", r.outflow);
    w.Str("level", r.level);
    w.Str("actuator", r.actuator);
    if (r.nominal_setpoint) w.Key("nominal_setpoint", *r.nominal_setpoint);
    if (r.actuator_gain_m3s_per_unit) {
      w.Key("actuator_gain_m3s_per_unit", *r.actuator_gain_m3s_per_unit);
    }
    w.Key("nominal_inflow_m3s", r.nominal_inflow_m3s);
    w.Key("expected_delay_s", r.expected_delay_s);
    w.Key("level_min_m", r.level_min_m);
    w.Key("level_max_m", r.level_max_m);
    w.List("online_models", r.online_models);
    w.Key("min_delay_s", r.min_delay_s);
    w.Key("max_delay_s", r.max_delay_s);
    w.Key("forgetting", r.forgetting);
    if (r.initial_covariance) w.Key("initial_covariance", *r.initial_covariance);
    w.Key("rls_method", config::EnumName(r.rls_method));
    w.Key("closed_loop", config::EnumName(r.closed_loop));
    if (r.id_wave_front) w.Bool("id_wave_front", *r.id_wave_front);
    w.List("batch_models", r.batch_models);
    if (r.idz_p22_s_per_m2) w.Key("idz_p22_s_per_m2", *r.idz_p22_s_per_m2);
    if (r.idz_p22_std_s_per_m2) w.Key("idz_p22_std_s_per_m2", *r.idz_p22_std_s_per_m2);
    if (!r.actuator_position.empty()) w.Str("actuator_position", r.actuator_position);
    w.Int("arx_na", r.arx_na);
    w.Int("arx_nb", r.arx_nb);
    w.Numbers("fractional_alphas", r.fractional_alphas);
    w.Key("fractional_delay_s", r.fractional_delay_s);
    if (!r.lpv_scheduling.empty()) w.Str("lpv_scheduling", r.lpv_scheduling);
    w.Int("lpv_na", r.lpv_na);
    w.Int("lpv_nb", r.lpv_nb);
    w.Key("lpv_delay_s", r.lpv_delay_s);
    w.Int("frac_ss_q", r.frac_ss_q);
    w.Key("frac_ss_delay_s", r.frac_ss_delay_s);
    w.Key("model_publish_period_s", r.model_publish_period_s);
  }
  for (const config::ExperimentConfig& e : c.experiments) {
    w.Line("");
    w.Line("[[experiment]]");
    w.Str("name", e.name);
    w.Str("reach", e.reach);
    w.Key("mode", config::EnumName(e.mode));
    if (e.mode == config::ExperimentMode::kDesign) {
      w.Key("amplitude_percent", e.amplitude_percent);
      w.Key("duration_factor", e.duration_factor);
    } else if (e.mode == config::ExperimentMode::kStep) {
      w.Key("amplitude", e.amplitude);
      w.Key("hold_s", e.hold_s);
    } else {
      w.Key("amplitude", e.amplitude);
      w.Key("clock_period_s", e.clock_period_s);
      w.Int("order", e.order);
      w.Int("periods", e.periods);
    }
    if (e.mode != config::ExperimentMode::kStep) w.Int("seed", e.seed);
    w.Key("settle_s", e.settle_s);
    w.Key("start", config::EnumName(e.start));
    w.Int("max_invalid_samples", e.max_invalid_samples);
    w.Key("max_sample_gap_periods", e.max_sample_gap_periods);
    w.Strings("with", e.with);
  }
  w.Line("");
  w.Line("[commands]");
  w.Bool("enabled", c.commands.enabled);
  w.Str("key_file", c.commands.key_file);
  w.Key("max_clock_skew_s", c.commands.max_clock_skew_s);
  w.List("accepted", c.commands.accepted);
  return w.Take();
}

}  // namespace canalid::daemon
