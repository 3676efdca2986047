#include "daemon/config/config_loader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/canalidd/driver_config.h"
#include "daemon/canalidd/plan_builder.h"
#include "daemon/config/plan_from_config.h"

namespace canalid::daemon {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// The smallest valid file: lines are numbered in the comments so positions can be checked.
const std::string kMinimal = R"([[plc]]
name = "p"
host = "127.0.0.1"

[[channel]]
name = "level"
plc = "p"
role = "level"
register = "input"
address = 10
type = "i16"
scale = 0.001
)";
// line 1 [[plc]], 5 [[channel]], 13 is the first line after it.

std::vector<std::string> Issues(const std::string& text) {
  try {
    ParseDaemonConfig(text, "t.toml");
  } catch (const ConfigError& e) {
    std::vector<std::string> out;
    for (const ConfigIssue& issue : e.issues()) out.push_back(issue.ToString());
    return out;
  }
  return {};
}

TEST(ConfigLoaderTest, MinimalFileTakesTheDefaults) {
  const config::DaemonConfig c = ParseDaemonConfig(kMinimal, "t.toml");
  EXPECT_EQ(c.daemon.state_directory, "/var/lib/canalidd");
  EXPECT_EQ(c.daemon.log_level, config::LogLevel::kInfo);
  EXPECT_EQ(c.daemon.time_scale, 1.0);
  EXPECT_FALSE(c.daemon.heartbeat.has_value());
  EXPECT_EQ(c.lcm.url, "");
  EXPECT_EQ(c.lcm.channel_prefix, "CANALID_");
  ASSERT_EQ(c.plcs.size(), 1u);
  EXPECT_EQ(c.plcs[0].transport, config::PlcTransport::kTcp);
  EXPECT_EQ(c.plcs[0].port, 502);
  EXPECT_EQ(c.plcs[0].poll_period_s, 1.0);
  ASSERT_EQ(c.channels.size(), 1u);
  EXPECT_EQ(c.channels[0].type, drivers::RegisterType::kI16);
  EXPECT_EQ(c.channels[0].scale, 0.001);
  EXPECT_EQ(c.channels[0].valid_min, -INFINITY);
  EXPECT_FALSE(c.commands.enabled);
  EXPECT_EQ(c.commands.accepted.size(), 4u);
}

TEST(ConfigLoaderTest, SyntaxErrorIsReportedWithItsPosition) {
  const auto issues = Issues("[daemon]\nlog_level = \"info\nx = 1\n");
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_THAT(issues[0], HasSubstr("t.toml:2:"));
}

TEST(ConfigLoaderTest, UnknownKeysAndTablesAreErrors) {
  EXPECT_THAT(Issues("[deamon]\n" + kMinimal + "bogus = 1\n"),
              ElementsAre("t.toml:1:2: deamon: unknown key (allowed: daemon, lcm, results, plc, "
                          "channel, reach, experiment, commands)",
                          "t.toml:14:1: channel[0].bogus: unknown key (allowed: name, plc, role, "
                          "register, address, type, word_order, scale, offset, unit, valid_min, "
                          "valid_max, writable)"));
}

TEST(ConfigLoaderTest, WrongTypesAndUnknownNames) {
  std::string text = "[daemon]\ntime_scale = \"fast\"\nlog_level = \"verbose\"\n" + kMinimal;
  text.replace(text.find("address = 10"), 12, "address = 1.5");
  EXPECT_THAT(Issues(text),
              ElementsAre("t.toml:2:14: daemon.time_scale: expected a number, got a string",
                          "t.toml:3:13: daemon.log_level: \"verbose\" is not allowed (allowed: "
                          "error, warn, info, debug)",
                          "t.toml:13:11: channel[0].address: expected an integer, got a float"));
}

TEST(ConfigLoaderTest, MissingRequiredKeysPointAtTheirTable) {
  EXPECT_THAT(Issues("[[plc]]\nname = \"p\"\n\n[[channel]]\nname = \"c\"\nplc = \"p\"\n"),
              ElementsAre("t.toml:1:1: plc[0].host: missing (required)",
                          "t.toml:4:1: channel[0].role: missing (required)",
                          "t.toml:4:1: channel[0].register: missing (required)",
                          "t.toml:4:1: channel[0].address: missing (required)",
                          "t.toml:4:1: channel[0].type: missing (required)"));
}

TEST(ConfigLoaderTest, KeysOfTheOtherTransportOrModeAreErrors) {
  std::string text = kMinimal;
  text.replace(text.find("host"), 4, "baud = 9600\nhost");
  EXPECT_THAT(Issues(text),
              ElementsAre("t.toml:3:1: plc[0].baud: only allowed when transport = \"rtu\""));
  EXPECT_THAT(Issues("[[plc]]\nname = \"p\"\ntransport = \"rtu\"\nhost = \"h\"\n"
                     "device = \"/dev/ttyS0\"\nparity = \"X\"\n" +
                     kMinimal.substr(kMinimal.find("[[channel]]"))),
              ElementsAre("t.toml:4:1: plc[0].host: only allowed when transport = \"tcp\"",
                          "t.toml:6:10: plc[0].parity: \"X\" is not a parity (allowed: \"N\", "
                          "\"E\", \"O\")"));
  EXPECT_THAT(Issues(kMinimal + "setpoint_max = 2.0\n"),
              ElementsAre("t.toml:13:1: channel[0].setpoint_max: only allowed when writable = "
                          "true"));
}

TEST(ConfigLoaderTest, WritableChannelNeedsItsLimits) {
  EXPECT_THAT(Issues(kMinimal + "writable = true\nsetpoint_max = 2.0\n"),
              ElementsAre("t.toml:5:1: channel[0].setpoint_min: missing (required)",
                          "t.toml:5:1: channel[0].max_rate_per_s: missing (required)",
                          "t.toml:13:12: channel[0].writable: an input register cannot be "
                          "written (allowed: register = \"holding\")"));
}

TEST(ConfigLoaderTest, RangesAndDanglingReferencesAreReportedAtTheirValues) {
  EXPECT_THAT(
      Issues(kMinimal + R"(
[[channel]]
name = "level"
plc = "q"
role = "flow"
register = "holding"
address = 70000
type = "u16"
)"),
      ElementsAre("t.toml:15:8: channel[1].name: duplicate channel name \"level\"",
                  "t.toml:16:7: channel[1].plc: unknown plc \"q\" (allowed: a [[plc]] name)",
                  "t.toml:19:11: channel[1].address: 70000 is out of range (allowed: 0..65535)"));
}

TEST(ConfigLoaderTest, ReachAndExperimentReferences) {
  EXPECT_THAT(Issues(kMinimal + R"(
[[reach]]
name = "r"
inflow = "level"
outflow = "nope"
level = "level"
actuator = "level"
nominal_inflow_m3s = 10
expected_delay_s = 600
level_min_m = 1.9
level_max_m = 2.3
online_models = ["id", "ar"]

[[experiment]]
name = "e"
reach = "r2"
amplitude = 0.1
)"),
              ElementsAre("t.toml:16:10: reach[0].inflow: channel \"level\" has role \"level\" "
                          "(allowed: \"flow\")",
                          "t.toml:17:11: reach[0].outflow: unknown channel \"nope\" (allowed: a "
                          "[[channel]] name)",
                          "t.toml:19:12: reach[0].actuator: channel \"level\" has role \"level\" "
                          "(allowed: \"gate\" or \"pump\")",
                          "t.toml:19:12: reach[0].actuator: channel \"level\" is not writable "
                          "(allowed: writable = true)",
                          "t.toml:24:24: reach[0].online_models[1]: \"ar\" is not allowed "
                          "(allowed: id, arx, frac-foptd, lpv, idz, frac-ss)",
                          "t.toml:28:9: experiment[0].reach: unknown reach \"r2\" (allowed: a "
                          "[[reach]] name)",
                          "t.toml:29:1: experiment[0].amplitude: only allowed when mode = "
                          "\"explicit\""));
}

TEST(ConfigLoaderTest, CommandsKeyFileRequiredWhenEnabled) {
  EXPECT_THAT(Issues("[commands]\nenabled = true\n" + kMinimal),
              ElementsAre("t.toml:1:1: commands.key_file: \"\" is not an absolute path (allowed: "
                          "/..., required when enabled)"));
}

TEST(ConfigLoaderTest, EmptyFileNeedsAPlc) {
  EXPECT_THAT(Issues(""), ElementsAre("t.toml:1:1: plc: no [[plc]] table (allowed: at least one)"));
}

TEST(ConfigLoaderTest, DaemonLcmAndCommandsSections) {
  EXPECT_THAT(Issues(R"([daemon]
state_directory = "var/lib"
time_scale = 20000
[daemon.heartbeat]
channel = "level"
period_s = 0
[lcm]
url = "http://x"
channel_prefix = "SITE-1"
[commands]
max_clock_skew_s = -1
accepted = ["start_experiment", "reboot"]
)" + kMinimal),
              ElementsAre("t.toml:2:19: daemon.state_directory: \"var/lib\" is not an absolute "
                          "path (allowed: /...)",
                          "t.toml:3:14: daemon.time_scale: 20000 is out of range (allowed: (0, "
                          "10000])",
                          "t.toml:5:11: daemon.heartbeat.channel: channel \"level\" is not a "
                          "writable heartbeat channel (allowed: role = \"heartbeat\", writable = "
                          "true)",
                          "t.toml:6:12: daemon.heartbeat.period_s: 0 is out of range (allowed: (0, "
                          "3600])",
                          "t.toml:8:7: lcm.url: \"http://x\" is not an LCM URL (allowed: \"\", "
                          "udpm://, memq://, file://, tcpq://)",
                          "t.toml:9:18: lcm.channel_prefix: \"SITE-1\" is not a channel prefix "
                          "(allowed: 0 to 32 of A-Z a-z 0-9 _)",
                          "t.toml:11:20: commands.max_clock_skew_s: -1 is out of range (allowed: "
                          "(0, 3600])",
                          "t.toml:12:33: commands.accepted[1]: \"reboot\" is not allowed "
                          "(allowed: start_experiment, abort_experiment, reset_estimator, "
                          "publish_config)"));
}

TEST(ConfigLoaderTest, ResultsSectionIsCheckedWithPositions) {
  EXPECT_THAT(Issues("[results]\nlisten = \"localhost\"\nmax_clients = 0\n" + kMinimal),
              ElementsAre("t.toml:2:10: results.listen: \"localhost\" is not an address to listen "
                          "on (allowed: \"host:port\" or \"[IPv6]:port\", port 0..65535)",
                          "t.toml:3:15: results.max_clients: 0 is out of range (allowed: 1..512)"));
  EXPECT_THAT(Issues("[results]\nlisten = \"::1:1503\"\nport = 1\n" + kMinimal),
              ElementsAre("t.toml:2:10: results.listen: \"::1:1503\" is not an address to listen "
                          "on (allowed: \"host:port\" or \"[IPv6]:port\", port 0..65535)",
                          "t.toml:3:1: results.port: unknown key (allowed: listen, max_clients)"));
  const config::DaemonConfig c = ParseDaemonConfig(
      "[results]\nlisten = \"[::1]:1503\"\nmax_clients = 8\n" + kMinimal, "t.toml");
  EXPECT_EQ(c.results.listen, "[::1]:1503");
  EXPECT_EQ(c.results.max_clients, 8);
  const auto address = config::ParseListenAddress(c.results.listen);
  ASSERT_TRUE(address.has_value());
  EXPECT_EQ(address->host, "::1");
  EXPECT_EQ(address->port, 1503);
  EXPECT_FALSE(config::ParseListenAddress("127.0.0.1:65536"));
  EXPECT_FALSE(config::ParseListenAddress("127.0.0.1:"));
  EXPECT_FALSE(config::ParseListenAddress(":1503"));
  EXPECT_FALSE(config::ParseListenAddress("[::1]1503"));
  // The plan serves the map only when listen is set.
  EXPECT_TRUE(daemon::BuildDaemonPlan(c, "t.toml", "").results_enabled);
  EXPECT_FALSE(
      daemon::BuildDaemonPlan(ParseDaemonConfig(kMinimal, "t.toml"), "t.toml", "").results_enabled);
}

TEST(ConfigLoaderTest, RtuPlc) {
  const std::string channel = kMinimal.substr(kMinimal.find("[[channel]]"));
  const config::DaemonConfig c = ParseDaemonConfig(
      "[[plc]]\nname = \"p\"\ntransport = \"rtu\"\ndevice = \"/dev/ttyUSB0\"\nbaud = 9600\n"
      "parity = \"N\"\ndata_bits = 7\nstop_bits = 2\nunit_id = 17\n" +
          channel,
      "t.toml");
  EXPECT_EQ(c.plcs[0].transport, config::PlcTransport::kRtu);
  EXPECT_EQ(c.plcs[0].device, "/dev/ttyUSB0");
  EXPECT_EQ(c.plcs[0].baud, 9600);
  EXPECT_EQ(c.plcs[0].parity, 'N');
  EXPECT_EQ(c.plcs[0].data_bits, 7);
  EXPECT_EQ(c.plcs[0].stop_bits, 2);
  EXPECT_EQ(c.plcs[0].unit_id, 17);
  EXPECT_THAT(
      Issues("[[plc]]\nname = \"p\"\ntransport = \"rtu\"\nbaud = 100\ndata_bits = 9\n"
             "stop_bits = 3\nunit_id = 0\nresponse_timeout_s = 0.5\npoll_period_s = 0.5\n"
             "backoff_initial_s = 2\nbackoff_max_s = 1\n" +
             channel),
      ElementsAre("t.toml:1:1: plc[0].device: missing (required)",
                  "t.toml:4:8: plc[0].baud: 100 is out of range (allowed: 300..4000000)",
                  "t.toml:5:13: plc[0].data_bits: 9 is out of range (allowed: 5..8)",
                  "t.toml:6:13: plc[0].stop_bits: 3 is out of range (allowed: 1..2)",
                  "t.toml:7:11: plc[0].unit_id: 0 is out of range (allowed: 1..247)",
                  "t.toml:9:17: plc[0].poll_period_s: 0.5 is out of range (allowed: (0.5, "
                  "3600])",
                  "t.toml:11:17: plc[0].backoff_max_s: 1 is out of range (allowed: [2, 3600])"));
}

TEST(ConfigLoaderTest, ExplicitExperimentKeys) {
  const std::string reach = R"(
[[channel]]
name = "q"
plc = "p"
role = "flow"
register = "input"
address = 11
type = "i16"

[[channel]]
name = "gate"
plc = "p"
role = "gate"
register = "holding"
address = 100
type = "i16"
scale = 0.001
writable = true
setpoint_min = 0.05
setpoint_max = 40.0
max_rate_per_s = 0.005

[[reach]]
name = "r"
inflow = "q"
outflow = "q"
level = "level"
actuator = "gate"
nominal_inflow_m3s = 10
expected_delay_s = 600
level_min_m = 1.9
level_max_m = 2.3
)";
  // kMinimal is lines 1-12, `reach` 13-44 (setpoint_max on 32), the experiment from 45 on.
  EXPECT_THAT(Issues(kMinimal + reach + R"(
[[experiment]]
name = "e"
reach = "r"
mode = "explicit"
clock_period_s = 2.5
order = 40
seed = 4294967296
amplitude_percent = 5
)"),
              ElementsAre("t.toml:32:16: channel[2].setpoint_max: 40 does not fit register type "
                          "\"i16\" with this scale and offset",
                          "t.toml:46:1: experiment[0].amplitude: missing (required)",
                          "t.toml:50:18: experiment[0].clock_period_s: 2.5 is not a whole number "
                          "of samples (allowed: n * sample time 1 s, n >= 1)",
                          "t.toml:51:9: experiment[0].order: 40 is out of range (allowed: 2..31)",
                          "t.toml:52:8: experiment[0].seed: 4294967296 is out of range (allowed: "
                          "1..2147483647)",
                          "t.toml:53:1: experiment[0].amplitude_percent: only allowed when mode "
                          "= \"design\""));
}

TEST(ConfigLoaderTest, IntegersMustFitTheirField) {
  std::string text = kMinimal;
  text.replace(text.find("address = 10"), 12, "address = 9999999999");
  EXPECT_THAT(Issues(text), ElementsAre("t.toml:10:11: channel[0].address: 9999999999 is out of "
                                        "range (allowed: a 32-bit integer)"));
}

TEST(ConfigLoaderTest, PlcArrayMustBeAnArrayOfTables) {
  EXPECT_THAT(Issues("plc = 3\n"),
              // Validate's "no [[plc]] table" on the same key is not repeated.
              ElementsAre("t.toml:1:7: plc: expected an array of tables [[plc]], got an integer"));
}

TEST(ConfigLoaderTest, UnreadableFile) {
  try {
    LoadDaemonConfig("/nonexistent/canalidd.toml");
    FAIL() << "no exception";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/canalidd.toml:1:1: cannot read the file");
  }
}

config::DaemonConfig LoadShipped(const char* name) {
  return LoadDaemonConfig(std::string(CANALID_SOURCE_DIR) + "/config/" + name);
}

TEST(ConfigLoaderTest, ShippedConfigsLoadAndRoundTrip) {
  for (const char* name :
       {"canalidd.example.toml", "canalidd-asce2.toml", "canalidd-lab-flume.toml"}) {
    SCOPED_TRACE(name);
    config::DaemonConfig c;
    try {
      c = LoadShipped(name);
    } catch (const ConfigError& e) {
      FAIL() << e.what();
    }
    const std::string text = RenderDaemonConfig(c);
    const config::DaemonConfig again = ParseDaemonConfig(text, "rendered");
    EXPECT_TRUE(again == c) << text;
    EXPECT_EQ(RenderDaemonConfig(again), text);
  }
}

// Numbers whose shortest decimal form needs 17 digits, infinities, strings with escapes, RTU and
// explicit experiments: what the shipped files do not exercise.
TEST(ConfigLoaderTest, RoundTripIsExact) {
  config::DaemonConfig c = LoadShipped("canalidd-asce2.toml");
  c.daemon.heartbeat->period_s = 0.1 + 0.2;  // 0.30000000000000004
  c.daemon.state_directory = "/var/lib/can\"al\\idd\t";
  c.lcm.url = "udpm://239.255.76.67:7667?ttl=1";
  config::PlcConfig& plc = c.plcs[0];
  plc.transport = config::PlcTransport::kRtu;
  plc.host = "127.0.0.1";  // the defaults of the keys an RTU file cannot have
  plc.port = 502;
  plc.connect_timeout_s = 1.0;
  plc.device = "/dev/ttyUSB0";
  plc.parity = 'N';
  plc.stop_bits = 2;
  c.channels[1].scale = 1.0 / 3.0;
  c.channels[1].offset = -1e-300;
  c.reaches[0].nominal_setpoint = 0.7;
  c.reaches[0].actuator_gain_m3s_per_unit = 14.5;
  c.reaches[0].online_models = {};
  c.reaches[0].rls_method = core::RlsMethod::kNlms;
  config::ExperimentConfig& e = c.experiments.emplace_back();
  e.name = "x";
  e.reach = "pool2";
  e.mode = config::ExperimentMode::kExplicit;
  e.amplitude = 0.05;
  e.clock_period_s = 360.0;  // a whole number of the demo's 60 s samples
  e.order = 5;
  e.periods = 3;
  e.seed = 2147483647;
  c.commands.enabled = true;
  c.commands.key_file = "/etc/canalidd/key";
  c.commands.accepted = {drivers::CommandKind::kAbortExperiment};
  for (const config::ConfigProblem& p : config::Validate(c))
    ADD_FAILURE() << p.path << ": " << p.message;
  const std::string text = RenderDaemonConfig(c);
  EXPECT_TRUE(ParseDaemonConfig(text, "rendered") == c) << text;
  EXPECT_THAT(text, HasSubstr("period_s = 0.30000000000000004\n"));
  EXPECT_THAT(text, HasSubstr("max_rate_per_s = inf\n"));
}

std::string ReadSource(const char* relative) {
  std::ifstream in(std::string(CANALID_SOURCE_DIR) + "/" + relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every key the renderer writes (both transports, both modes, every optional key) is documented
// in the example file, as `key =` either live or in a comment, and in docs/configuration.md as a
// table row.
TEST(ConfigLoaderTest, ExampleAndDocsDocumentEveryKey) {
  const std::string example = ReadSource("config/canalidd.example.toml");
  const std::string docs = ReadSource("docs/configuration.md");
  config::DaemonConfig c = LoadShipped("canalidd.example.toml");
  config::PlcConfig rtu = c.plcs[0];
  rtu.transport = config::PlcTransport::kRtu;
  c.plcs.push_back(rtu);
  c.reaches[0].nominal_setpoint = 1.0;
  c.reaches[0].actuator_gain_m3s_per_unit = 1.0;
  c.reaches[0].initial_covariance = 1.0;
  std::set<std::string> keys;
  std::istringstream rendered(RenderDaemonConfig(c));
  for (std::string line; std::getline(rendered, line);) {
    const std::size_t eq = line.find(" = ");
    if (eq != std::string::npos) keys.insert(line.substr(0, eq));
  }
  EXPECT_GE(keys.size(), 60u);
  for (const std::string& key : keys) {
    EXPECT_TRUE(example.find("\n" + key + " = ") != std::string::npos ||
                example.find(" " + key + " = ") != std::string::npos)
        << key;
    EXPECT_NE(docs.find("| `" + key + "` |"), std::string::npos) << key;
  }
}

// The asce2 demo file against docs/register-map.md: pool record r of the float input block at
// 300 + 16 r + 2 field (fields 0 inflow, 1 outflow, 2 downstream level, 3 gate position), the
// gate setpoint of record r at holding 300 + 4 r; pool 2 is record 1, its inflow gate record 0.
TEST(ConfigLoaderTest, Asce2MapsOntoThePoller) {
  const config::DaemonConfig c = LoadShipped("canalidd-asce2.toml");
  ASSERT_EQ(c.plcs.size(), 1u);
  const drivers::PollerConfig poller = BuildPollerConfig(c, c.plcs[0]);
  EXPECT_EQ(poller.plc_name, "asce2");
  EXPECT_DOUBLE_EQ(poller.period_s, 0.1);
  ASSERT_EQ(poller.channels.size(), 6u);
  struct Expected {
    const char* name;
    drivers::RegisterKind kind;
    int address;
  };
  const Expected expected[] = {{"heartbeat", drivers::RegisterKind::kHolding, 0},
                               {"pool2_inflow", drivers::RegisterKind::kInput, 316},
                               {"pool2_outflow", drivers::RegisterKind::kInput, 318},
                               {"pool2_level", drivers::RegisterKind::kInput, 320},
                               {"gate1_position", drivers::RegisterKind::kInput, 306},
                               {"gate1_setpoint", drivers::RegisterKind::kHolding, 300}};
  EXPECT_EQ(PollerChannelIndex(poller, "pool2_level"), 3);
  EXPECT_EQ(PollerChannelIndex(poller, "nope"), -1);
  for (std::size_t i = 0; i < poller.channels.size(); ++i) {
    EXPECT_EQ(poller.channels[i].name, expected[i].name);
    EXPECT_EQ(poller.channels[i].kind, expected[i].kind) << expected[i].name;
    EXPECT_EQ(poller.channels[i].address, expected[i].address) << expected[i].name;
  }
  // 2.1 m as canalsim serves it (docs/register-map.md: 0x4006 0x6666, abcd) decodes to 2.1 m.
  const uint16_t level_registers[] = {0x4006, 0x6666};
  const drivers::DecodedValue level =
      drivers::DecodeChannel(poller.channels[3].scaling, level_registers);
  ASSERT_TRUE(level.ok());
  EXPECT_NEAR(level.value, 2.1, 1e-6);  // float32 resolution near 2 m is 2.4e-7 m
  const drivers::PollChannel& gate = poller.channels[5];
  EXPECT_TRUE(gate.writable);
  EXPECT_DOUBLE_EQ(gate.limits.min_value, 0.05);
  EXPECT_DOUBLE_EQ(gate.limits.max_value, 2.0);
  // 0.005 m per plant second at 600 plant seconds per wall second.
  EXPECT_DOUBLE_EQ(gate.limits.max_rate_per_s, 3.0);
  EXPECT_TRUE(poller.channels[0].writable);
  EXPECT_TRUE(std::isinf(poller.channels[0].limits.max_rate_per_s));
  drivers::ValidatePollerConfig(poller, c.plcs[0].response_timeout_s);

  const auto link = BuildModbusConfig(c.plcs[0]);
  ASSERT_TRUE(std::holds_alternative<drivers::ModbusTcpConfig>(link));
  const auto& tcp = std::get<drivers::ModbusTcpConfig>(link);
  EXPECT_EQ(tcp.host, "127.0.0.1");
  EXPECT_EQ(tcp.port, 1502);
  EXPECT_DOUBLE_EQ(tcp.response_timeout_s, 0.05);
  drivers::ValidateModbusConfig(tcp);

  // The demo's experiment: Ts = 0.1 s x 600 = 60 s; clock round(682 / 120) = 6 samples; order 6
  // (63 x 360 s = 22680 s >= 20 x 682 s, order 5's 11160 s is not); 10 samples of settling.
  const core::ExperimentPlan plan = config::BuildExperimentPlan(c, c.experiments[0], 0.9);
  EXPECT_EQ(plan.prbs.clock_period_samples, 6);
  EXPECT_EQ(plan.prbs.order, 6);
  EXPECT_EQ(plan.excite_samples, 378);
  EXPECT_EQ(plan.settle_samples, 10);
  EXPECT_DOUBLE_EQ(plan.level_min_m, 1.9);
  EXPECT_DOUBLE_EQ(plan.level_max_m, 2.3);
}

TEST(ConfigLoaderTest, RtuLinkSettings) {
  config::PlcConfig plc;
  plc.transport = config::PlcTransport::kRtu;
  plc.device = "/dev/ttyUSB1";
  plc.baud = 9600;
  plc.parity = 'O';
  plc.stop_bits = 2;
  plc.unit_id = 7;
  const auto link = BuildModbusConfig(plc);
  ASSERT_TRUE(std::holds_alternative<drivers::ModbusRtuConfig>(link));
  const auto& rtu = std::get<drivers::ModbusRtuConfig>(link);
  EXPECT_EQ(rtu.device, "/dev/ttyUSB1");
  EXPECT_EQ(rtu.baud, 9600);
  EXPECT_EQ(rtu.parity, 'O');
  EXPECT_EQ(rtu.stop_bits, 2);
  EXPECT_EQ(rtu.unit_id, 7);
}

}  // namespace
}  // namespace canalid::daemon
