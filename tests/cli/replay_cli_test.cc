// `canalid replay` and `canalid export` run as programs on LCM logs written here with LCM's own
// writer (lcm::LogFile): the daemon's configuration config/canalidd-asce2.toml, then one sample
// per row (channels CANALID_ASCE2_*, the config's prefix) of canalsim's PRBS record of ASCE canal 2
// pool 2 (tests/data/sim, Ts = 60 s, the config's 0.1 s poll x 600).  The truths: the record itself
// (export must give back its values), and replays of logs holding only the events before a cut or
// damage, written separately (a damaged log must give exactly what its intact part gives), with the
// damage's byte offset computed here from the event sizes (28 header bytes + channel + data per
// event).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <canalid/config_t.hpp>
#include <canalid/model_snapshot_t.hpp>
#include <canalid/sample_t.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kStartUtime = 1'700'000'000'000'000;
constexpr std::int64_t kPollUs = 100'000;  // poll_period_s = 0.1 of the config

struct Event {
  std::string channel;
  std::vector<std::uint8_t> data;
  std::int64_t utime = 0;
};

struct Row {
  double q_in, q_out, level;
};

std::string SourceFile(const std::string& relative) {
  return std::string(CANALID_SOURCE_DIR) + "/" + relative;
}

// time_s,q_in,q_out,level rows, parsed here without canalid's CSV reader.
std::vector<Row> PrbsRecord() {
  std::ifstream in(SourceFile("tests/data/sim/asce2-pool2-prbs.csv"));
  std::string line;
  std::getline(in, line);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string t, a, b, c;
    std::getline(s, t, ',');
    std::getline(s, a, ',');
    std::getline(s, b, ',');
    std::getline(s, c, ',');
    rows.push_back({std::stod(a), std::stod(b), std::stod(c)});
  }
  return rows;
}

template <class Message>
std::vector<std::uint8_t> Encode(const Message& m) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

Event ConfigEvent(std::int64_t utime) {
  canalid::config_t c;
  c.utime = utime;
  c.path = "config/canalidd-asce2.toml";
  c.version = "test";
  c.text = ReadFile(SourceFile("config/canalidd-asce2.toml"));
  return {"CANALID_ASCE2_CONFIG", Encode(c), utime};
}

Event SampleEvent(std::int64_t sequence, std::int64_t utime, const Row& row) {
  canalid::sample_t s;
  s.utime = utime;
  s.sequence = sequence;
  s.source = "asce2";
  s.status = canalid::sample_t::STATUS_OK;
  s.channel_names = {"heartbeat",   "pool2_inflow",   "pool2_outflow",
                     "pool2_level", "gate1_position", "gate1_setpoint"};
  s.values = {0.0, row.q_in, row.q_out, row.level, 1.5, 1.5};
  s.num_channels = static_cast<std::int32_t>(s.values.size());
  s.quality.assign(s.values.size(), int8_t{canalid::sample_t::QUALITY_VALID});
  return {"CANALID_ASCE2_SAMPLE_asce2", Encode(s), utime};
}

Event ModelEvent(std::int64_t utime, double area) {
  canalid::model_snapshot_t m;
  m.utime = utime;
  m.reach = "pool2";
  m.model_kind = "id";
  m.estimator = "rls-bank";
  m.samples_used = 7;
  m.param_names = {"delay_s", "area_m2"};
  m.param_values = {660.0, area};
  m.param_std_devs = {NAN, 0.5};
  m.num_params = 2;
  return {"CANALID_ASCE2_MODEL_pool2", Encode(m), utime};
}

// One daemon run: its configuration, then a sample per row, sequences from 0.
std::vector<Event> DaemonRun(const std::vector<Row>& rows, std::int64_t start_utime,
                             bool config = true) {
  std::vector<Event> events;
  if (config) events.push_back(ConfigEvent(start_utime));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto i = static_cast<std::int64_t>(k);
    events.push_back(SampleEvent(i, start_utime + 1000 + i * kPollUs, rows[k]));
  }
  return events;
}

// Writes events[0, count) with lcm::LogFile; returns each event's offset in the file.
std::vector<std::uint64_t> WriteLog(const fs::path& path, const std::vector<Event>& events,
                                    std::size_t count) {
  lcm::LogFile log(path.string(), "w");
  EXPECT_TRUE(log.good()) << path;
  std::vector<std::uint64_t> offsets;
  std::uint64_t offset = 0;
  for (std::size_t i = 0; i < count; ++i) {
    lcm::LogEvent e;
    e.eventnum = static_cast<std::int64_t>(i);
    e.timestamp = events[i].utime;
    e.channel = events[i].channel;
    e.datalen = static_cast<std::int32_t>(events[i].data.size());
    e.data = const_cast<std::uint8_t*>(events[i].data.data());
    EXPECT_EQ(log.writeEvent(&e), 0);
    offsets.push_back(offset);
    offset += 28 + events[i].channel.size() + events[i].data.size();
  }
  return offsets;
}

std::vector<char> Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void PutBytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string LastLine(const std::string& out) {
  if (out.empty()) return {};
  const std::size_t end = out.back() == '\n' ? out.size() - 1 : out.size();
  const std::size_t start = out.rfind('\n', end == 0 ? 0 : end - 1);
  return out.substr(start == std::string::npos ? 0 : start + 1,
                    end - (start == std::string::npos ? 0 : start + 1));
}

ProgramRun Replay(const fs::path& dir, const fs::path& log, const std::string& args = "") {
  return RunProgram(CanalidProgram() + " replay " + log.string() + " " + args, dir);
}

TEST(ReplayCli, ReplaysARunToItsBatchModelThenPrintsItLast) {
  const fs::path dir = TestDirectory("replay-full");
  const std::vector<Event> events = DaemonRun(PrbsRecord(), kStartUtime);
  WriteLog(dir / "run.lcmlog", events, events.size());
  const ProgramRun run = Replay(dir, dir / "run.lcmlog");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The config's on_start experiment records 378 samples after 10 of settling and identifies
  // them: the batch lines (id, idz), then the final model (the id one) as JSON.
  EXPECT_NE(run.out.find("pool2  batch id: delay "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("pool2  batch idz: area_m2 "), std::string::npos) << run.out;
  const nlohmann::json model = nlohmann::json::parse(LastLine(run.out), nullptr, false);
  ASSERT_TRUE(model.is_object()) << run.out;
  EXPECT_EQ(model.value("model", ""), "id");
  EXPECT_EQ(model.value("reach", ""), "pool2");
  EXPECT_EQ(model.value("sample_time_s", 0.0), 60.0);
  // 841 samples, every one used.
  EXPECT_NE(run.err.find("841 samples of 842 events"), std::string::npos) << run.err;

  const ProgramRun json = Replay(dir, dir / "run.lcmlog", "--json --snapshot-every 100");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  std::istringstream lines(json.out);
  std::string line;
  int online = 0, batch = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    ASSERT_TRUE(j.is_object()) << line;
    online += j.value("estimator", "") == "online";
    batch += j.value("estimator", "") == "batch";
  }
  EXPECT_EQ(online, 8);  // samples 100, 200 ... 800
  EXPECT_EQ(batch, 2);   // the demo's batch_models: id and idz
  EXPECT_EQ(LastLine(json.out), LastLine(run.out));

  // A window of the log: polls 0.1 s apart, so [20 s, 30 s] after the first holds 101 of them.
  const ProgramRun window = Replay(dir, dir / "run.lcmlog", "--from 20 --to 30");
  ASSERT_EQ(window.exit_code, 0) << window.err;
  EXPECT_NE(window.err.find("101 samples of 842 events"), std::string::npos) << window.err;
}

TEST(ReplayCli, TruncatedLogGivesWhatItsWholeEventsGive) {
  const fs::path dir = TestDirectory("replay-truncated");
  const std::vector<Event> events = DaemonRun(PrbsRecord(), kStartUtime);
  const std::size_t cut_event = 600;  // after the batch model: the final line is that model
  const std::vector<std::uint64_t> offsets = WriteLog(dir / "whole.lcmlog", events, events.size());
  WriteLog(dir / "prefix.lcmlog", events, cut_event);
  std::vector<char> bytes = Bytes(dir / "whole.lcmlog");
  bytes.resize(offsets[cut_event] + 40);  // into the channel name of event 600
  PutBytes(dir / "cut.lcmlog", bytes);

  const ProgramRun expected = Replay(dir, dir / "prefix.lcmlog");
  ASSERT_EQ(expected.exit_code, 0) << expected.err;
  const ProgramRun cut = Replay(dir, dir / "cut.lcmlog");
  EXPECT_EQ(cut.exit_code, 0) << cut.err;  // a log cut short is a warning
  EXPECT_NE(cut.err.find("byte " + std::to_string(offsets[cut_event]) + ": event 600 needs"),
            std::string::npos)
      << cut.err;
  EXPECT_EQ(LastLine(cut.out), LastLine(expected.out));
  EXPECT_FALSE(LastLine(cut.out).empty());
}

TEST(ReplayCli, CorruptLogGivesWhatItsIntactPartGivesAndExits2) {
  const fs::path dir = TestDirectory("replay-corrupt");
  const std::vector<Event> events = DaemonRun(PrbsRecord(), kStartUtime);
  const std::size_t bad_event = 300;  // during the experiment: the final line is the online one
  const std::vector<std::uint64_t> offsets = WriteLog(dir / "whole.lcmlog", events, events.size());
  WriteLog(dir / "prefix.lcmlog", events, bad_event);
  std::vector<char> bytes = Bytes(dir / "whole.lcmlog");
  bytes[offsets[bad_event] + 2] = 0;  // the sync word
  PutBytes(dir / "bad.lcmlog", bytes);

  const ProgramRun expected = Replay(dir, dir / "prefix.lcmlog");
  ASSERT_EQ(expected.exit_code, 0) << expected.err;
  const ProgramRun bad = Replay(dir, dir / "bad.lcmlog");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(
      bad.err.find("bad.lcmlog: byte " + std::to_string(offsets[bad_event]) + ": not an LCM event"),
      std::string::npos)
      << bad.err;
  EXPECT_EQ(LastLine(bad.out), LastLine(expected.out));
  const nlohmann::json online = nlohmann::json::parse(LastLine(bad.out), nullptr, false);
  ASSERT_TRUE(online.is_object()) << bad.out;
  EXPECT_EQ(online.value("estimator", ""), "online");

  // A well-framed event whose message does not decode is damage too.
  std::vector<Event> garbled = events;
  garbled[bad_event].data.resize(10);
  WriteLog(dir / "garbled.lcmlog", garbled, garbled.size());
  const ProgramRun undecodable = Replay(dir, dir / "garbled.lcmlog");
  EXPECT_EQ(undecodable.exit_code, 2) << undecodable.err;
  EXPECT_NE(undecodable.err.find("byte " + std::to_string(offsets[bad_event]) +
                                 ": event 300 on CANALID_ASCE2_SAMPLE_asce2 does not decode"),
            std::string::npos)
      << undecodable.err;
  EXPECT_EQ(LastLine(undecodable.out), LastLine(expected.out));
}

TEST(ReplayCli, ADaemonRestartInTheLogStartsTheReachesAgain) {
  const fs::path dir = TestDirectory("replay-restart");
  const std::vector<Row> rows = PrbsRecord();
  std::vector<Event> events =
      DaemonRun(std::vector<Row>(rows.begin(), rows.begin() + 200), kStartUtime);
  const std::vector<Event> second = DaemonRun(rows, kStartUtime + 60'000'000);
  events.insert(events.end(), second.begin(), second.end());
  WriteLog(dir / "two-runs.lcmlog", events, events.size());
  WriteLog(dir / "second.lcmlog", second, second.size());
  const ProgramRun expected = Replay(dir, dir / "second.lcmlog");
  ASSERT_EQ(expected.exit_code, 0) << expected.err;
  const ProgramRun both = Replay(dir, dir / "two-runs.lcmlog");
  ASSERT_EQ(both.exit_code, 0) << both.err;
  EXPECT_NE(both.err.find("the daemon restarted"), std::string::npos) << both.err;
  EXPECT_EQ(LastLine(both.out), LastLine(expected.out));
}

TEST(ReplayCli, ALogWithoutItsConfigurationNeedsConfig) {
  const fs::path dir = TestDirectory("replay-no-config");
  const std::vector<Row> rows = PrbsRecord();
  const std::vector<Event> with = DaemonRun(rows, kStartUtime);
  const std::vector<Event> without = DaemonRun(rows, kStartUtime, false);
  WriteLog(dir / "with.lcmlog", with, with.size());
  WriteLog(dir / "without.lcmlog", without, without.size());
  const ProgramRun refused = Replay(dir, dir / "without.lcmlog");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("no canalid configuration message"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--config"), std::string::npos) << refused.err;

  const ProgramRun given =
      Replay(dir, dir / "without.lcmlog", "--config " + SourceFile("config/canalidd-asce2.toml"));
  ASSERT_EQ(given.exit_code, 0) << given.err;
  const ProgramRun recorded = Replay(dir, dir / "with.lcmlog");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  EXPECT_EQ(LastLine(given.out), LastLine(recorded.out));

  const ProgramRun unknown = Replay(dir, dir / "with.lcmlog", "--reach pool9");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("--reach pool9: not a reach of the configuration (pool2)"),
            std::string::npos)
      << unknown.err;
}

TEST(ReplayCli, ProgressOnATerminalOnly) {
  ASSERT_TRUE(fs::exists("/usr/bin/script")) << "no script(1) for a pty (Debian bsdutils)";
  const fs::path dir = TestDirectory("replay-progress");
  const std::vector<Event> events = DaemonRun(PrbsRecord(), kStartUtime);
  WriteLog(dir / "run.lcmlog", events, events.size());
  // script(1) runs the replay on a pseudo-terminal and copies what it wrote.
  const ProgramRun tty = RunProgram("/usr/bin/script -qec '" + CanalidProgram() + " replay " +
                                        (dir / "run.lcmlog").string() + "' /dev/null",
                                    dir);
  EXPECT_EQ(tty.exit_code, 0) << tty.err;
  EXPECT_NE(tty.out.find("run.lcmlog: 100 %  841 samples"), std::string::npos) << tty.out;
  const ProgramRun plain = Replay(dir, dir / "run.lcmlog");
  EXPECT_EQ(plain.err.find(" %  "), std::string::npos) << plain.err;
}

// An operator's estimator reset, marked in the log by the daemon's "rls-bank-reset" model
// message, restarts the replay's online bank there: it has seen only the samples after it.
TEST(ReplayCli, AnEstimatorResetInTheLogRestartsTheOnlineBank) {
  const fs::path dir = TestDirectory("replay-reset");
  const std::vector<Row> rows = PrbsRecord();
  // 350 polls: the experiment (10 settling + 378 exciting) does not end, so the final line is
  // the online estimate.
  std::vector<Event> events =
      DaemonRun(std::vector<Row>(rows.begin(), rows.begin() + 350), kStartUtime);
  Event reset = ModelEvent(events[200].utime + 1, NAN);
  canalid::model_snapshot_t m;
  m.decode(reset.data.data(), 0, static_cast<int>(reset.data.size()));
  m.estimator = "rls-bank-reset";
  reset.data = Encode(m);
  events.insert(events.begin() + 201, reset);  // after the config and 200 samples
  WriteLog(dir / "reset.lcmlog", events, events.size());
  const ProgramRun run = Replay(dir, dir / "reset.lcmlog");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json online = nlohmann::json::parse(LastLine(run.out), nullptr, false);
  ASSERT_TRUE(online.is_object()) << run.out;
  EXPECT_EQ(online.value("estimator", ""), "online");
  EXPECT_EQ(online.value("samples", 0), 150);
}

// The export gives back the record's values exactly (17 significant digits) on the plant-time
// grid of the configuration, and the published models with their parameters.
TEST(ExportCli, WritesEachReachsSamplesAndTheModels) {
  const fs::path dir = TestDirectory("export");
  const std::vector<Row> rows = PrbsRecord();
  std::vector<Event> events = DaemonRun(rows, kStartUtime);
  events.push_back(ModelEvent(kStartUtime + 5'000'000, 34000.5));
  events.push_back(ModelEvent(kStartUtime + 6'000'000, 35000.25));
  WriteLog(dir / "run.lcmlog", events, events.size());
  const ProgramRun run = RunProgram(CanalidProgram() + " export " + (dir / "run.lcmlog").string() +
                                        " --out " + (dir / "csv").string(),
                                    dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("pool2.csv: 841 rows"), std::string::npos) << run.out;

  std::ifstream reach(dir / "csv" / "pool2.csv");
  std::string line;
  std::getline(reach, line);
  EXPECT_EQ(line, "time_s,pool2_inflow,pool2_outflow,pool2_level,gate1_setpoint,wall_time_s");
  std::size_t k = 0;
  while (std::getline(reach, line)) {
    std::istringstream s(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 6U) << line;
    ASSERT_LT(k, rows.size());
    EXPECT_EQ(v[0], 60.0 * static_cast<double>(k)) << line;
    EXPECT_EQ(v[1], rows[k].q_in) << line;
    EXPECT_EQ(v[2], rows[k].q_out) << line;
    EXPECT_EQ(v[3], rows[k].level) << line;
    EXPECT_EQ(v[4], 1.5) << line;
    ++k;
  }
  EXPECT_EQ(k, rows.size());

  const std::string models = ReadFile(dir / "csv" / "models.csv");
  EXPECT_EQ(models.substr(0, models.find('\n')),
            "wall_time_s,reach,model_kind,estimator,samples_used,delay_s,delay_s_std,area_m2,"
            "area_m2_std,trace_p,condition_number,excitation,prediction_error_rms,flags");
  EXPECT_NE(models.find(",pool2,id,rls-bank,7,660,nan,34000.5,0.5,"), std::string::npos) << models;
  EXPECT_NE(models.find(",pool2,id,rls-bank,7,660,nan,35000.25,0.5,"), std::string::npos) << models;
}

// `canalid report --input LOG`: the reach's samples exported to OUT/data and identified with the
// reach's channels as the default columns, giving what identify gives on that export.
TEST(ReportFromLogCli, ReportsOnTheReachOfALog) {
  const fs::path dir = TestDirectory("report-log");
  const std::vector<Event> events = DaemonRun(PrbsRecord(), kStartUtime);
  WriteLog(dir / "run.lcmlog", events, events.size());
  const ProgramRun run =
      RunProgram(CanalidProgram() + " report --input " + (dir / "run.lcmlog").string() +
                     " --model id --out " + (dir / "rep").string(),
                 dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(fs::exists(dir / "rep" / "index.html"));
  EXPECT_GT(fs::file_size(dir / "rep" / "fit_id.png"), 8000U);
  const ProgramRun identify =
      RunProgram(CanalidProgram() + " identify --model id --input " +
                     (dir / "rep" / "data" / "pool2.csv").string() +
                     " --qin pool2_inflow --qout pool2_outflow --level pool2_level",
                 dir);
  ASSERT_EQ(identify.exit_code, 0) << identify.err;
  const nlohmann::json expected = nlohmann::json::parse(identify.out);
  const nlohmann::json reported =
      nlohmann::json::parse(ReadFile(dir / "rep" / "models" / "id.json"));
  EXPECT_EQ(reported.at("area_m2"), expected.at("area_m2"));
  EXPECT_EQ(reported.at("delay_s"), expected.at("delay_s"));

  const ProgramRun unknown =
      RunProgram(CanalidProgram() + " report --input " + (dir / "run.lcmlog").string() +
                     " --reach pool7 --model id --out " + (dir / "rep2").string(),
                 dir);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("--reach pool7"), std::string::npos) << unknown.err;
}

}  // namespace
}  // namespace canalid::testing
